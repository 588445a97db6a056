"""Occupancy grid for mobile-base planning (ROS map_server YAML + PGM, inflation).

Conventions (relied on by ``astar.py``, ``se2.py``, ``mspp.py``, ``tunnel.py``
and ``biped/``):

- ``grid.occupied``: bool array, shape ``(height, width)``; **row = y index,
  col = x index**, row 0 is the cell at the map origin (the bottom row of the
  image, as in ``nav_msgs/OccupancyGrid``). Unknown cells are included in
  ``occupied`` when ``unknown_is_occupied`` (the default) and always listed in
  ``grid.unknown``.
- ``grid.resolution``: metres per cell; ``grid.origin``: ``(x, y, yaw)`` of the
  corner of cell (0, 0) in the map frame (map_server's ``origin``).
- ``grid.world_to_cell(x, y) -> (row, col)`` (ints, may be outside the map:
  check with ``grid.in_bounds(row, col)``); ``grid.cell_to_world(row, col) ->
  (x, y)`` (the cell centre).
- ``grid.inflate(radius) -> OccupancyGrid``: a cell becomes occupied when its
  centre lies within ``radius`` metres (inclusive) of the centre of an
  occupied cell: the convolution of the grid with a disc, exact to the cell
  (Euclidean distance transform). Space outside the map is not an obstacle.
- ``OccupancyGrid.from_yaml(path)``, ``grid.save_yaml(path)``,
  ``OccupancyGrid(occupied, resolution, origin)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from scipy import ndimage

FREE_VALUE = 0
OCCUPIED_VALUE = 100
UNKNOWN_VALUE = -1

# Pixel values map_saver writes (trinary mode).
PGM_FREE = 254
PGM_OCCUPIED = 0
PGM_UNKNOWN = 205


@dataclass
class OccupancyGrid:
    """A 2-D occupancy grid; see the module docstring for the conventions."""

    occupied: np.ndarray
    resolution: float = 1.0
    origin: tuple = (0.0, 0.0, 0.0)
    unknown: np.ndarray | None = None
    unknown_is_occupied: bool = True
    frame_id: str = "map"
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        occupied = np.asarray(self.occupied)
        if occupied.ndim != 2:
            raise ValueError(f"occupied must be a 2-D array (height, width), got shape {occupied.shape}")
        self.occupied = occupied.astype(bool, copy=True)
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise ValueError(f"resolution must be a positive number of metres per cell, got {self.resolution}")
        self.resolution = float(self.resolution)
        origin = tuple(float(v) for v in self.origin)
        if len(origin) == 2:
            origin = (*origin, 0.0)
        if len(origin) != 3 or not all(math.isfinite(v) for v in origin):
            raise ValueError(f"origin must be finite (x, y, yaw), got {self.origin}")
        self.origin = origin
        if self.unknown is None:
            self.unknown = np.zeros_like(self.occupied)
        else:
            self.unknown = np.asarray(self.unknown, dtype=bool)
            if self.unknown.shape != self.occupied.shape:
                raise ValueError(f"unknown has shape {self.unknown.shape}, occupied has {self.occupied.shape}")
        if self.unknown_is_occupied:
            self.occupied |= self.unknown

    # ------------------------------------------------------------------ shape
    @property
    def height(self) -> int:
        return self.occupied.shape[0]

    @property
    def width(self) -> int:
        return self.occupied.shape[1]

    @property
    def shape(self) -> tuple[int, int]:
        return self.occupied.shape

    @property
    def free(self) -> np.ndarray:
        return ~self.occupied

    # ------------------------------------------------------------ conversions
    def world_to_grid_frame(self, x: float, y: float) -> tuple[float, float]:
        """Map-frame point -> metres in the grid frame (origin corner, grid axes)."""
        ox, oy, yaw = self.origin
        dx, dy = x - ox, y - oy
        c, s = math.cos(yaw), math.sin(yaw)
        return c * dx + s * dy, -s * dx + c * dy

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """Map-frame point (metres) -> (row, col); may lie outside the map.

        A point within 1e-6 cell of a cell's lower edge belongs to that cell
        (so 1.0 m is cell 10 at 0.1 m despite rounding).
        """
        gx, gy = self.world_to_grid_frame(x, y)
        eps = 1e-6
        return int(math.floor(gy / self.resolution + eps)), int(math.floor(gx / self.resolution + eps))

    def cell_to_world(self, row: float, col: float) -> tuple[float, float]:
        """(row, col) -> map-frame centre of that cell (metres)."""
        gx, gy = (col + 0.5) * self.resolution, (row + 0.5) * self.resolution
        ox, oy, yaw = self.origin
        c, s = math.cos(yaw), math.sin(yaw)
        return ox + c * gx - s * gy, oy + s * gx + c * gy

    def cells_to_world(self, cells: np.ndarray) -> np.ndarray:
        """(n, 2) array of (row, col) -> (n, 2) array of map-frame (x, y) cell centres."""
        cells = np.asarray(cells, dtype=float).reshape(-1, 2)
        gx, gy = (cells[:, 1] + 0.5) * self.resolution, (cells[:, 0] + 0.5) * self.resolution
        ox, oy, yaw = self.origin
        c, s = math.cos(yaw), math.sin(yaw)
        return np.column_stack([ox + c * gx - s * gy, oy + s * gx + c * gy])

    def heading_to_grid(self, theta: float) -> float:
        """A map-frame heading expressed in the grid frame."""
        return theta - self.origin[2]

    def in_bounds(self, row: int, col: int) -> bool:
        return 0 <= row < self.height and 0 <= col < self.width

    def is_free_cell(self, row: int, col: int) -> bool:
        return self.in_bounds(row, col) and not self.occupied[row, col]

    # --------------------------------------------------------------- inflation
    def distance_to_obstacles(self) -> np.ndarray:
        """Metres from each cell centre to the nearest occupied cell centre (inf when none)."""
        if not self.occupied.any():
            return np.full(self.shape, np.inf)
        return ndimage.distance_transform_edt(~self.occupied) * self.resolution

    def inflate(self, radius: float) -> OccupancyGrid:
        """Obstacles grown by a disc of ``radius`` metres (inclusive, exact to the cell)."""
        if not (math.isfinite(radius) and radius >= 0):
            raise ValueError(f"inflation radius must be finite and >= 0, got {radius}")
        grown = self.distance_to_obstacles() <= radius + 1e-9 * self.resolution
        return self.with_occupied(grown)

    def with_occupied(self, occupied: np.ndarray) -> OccupancyGrid:
        """Same geometry, different occupancy (unknown cells carried over as information only)."""
        return OccupancyGrid(
            occupied, self.resolution, self.origin, self.unknown.copy(), False, self.frame_id, dict(self.meta)
        )

    # ---------------------------------------------------------- int8 values
    def to_values(self) -> np.ndarray:
        """nav_msgs-style int8 values (0 free, 100 occupied, -1 unknown), shape (height, width)."""
        values = np.where(self.occupied, OCCUPIED_VALUE, FREE_VALUE).astype(np.int8)
        values[self.unknown] = UNKNOWN_VALUE
        return values

    @classmethod
    def from_values(
        cls,
        values,
        width: int,
        height: int,
        resolution: float,
        origin=(0.0, 0.0, 0.0),
        *,
        occupied_threshold: int = 65,
        unknown_is_occupied: bool = True,
        frame_id: str = "map",
    ) -> OccupancyGrid:
        """From row-major int8 data as in ``nav_msgs/OccupancyGrid`` (value >= threshold = occupied)."""
        width, height = int(width), int(height)
        if width <= 0 or height <= 0:
            raise ValueError(f"map is empty ({width} x {height} cells)")
        data = np.asarray(values, dtype=np.int16).ravel()
        if data.size != width * height:
            raise ValueError(f"map data has {data.size} values, width x height = {width} x {height} = {width * height}")
        data = data.reshape(height, width)
        return cls(
            data >= occupied_threshold, resolution, origin, data < 0, unknown_is_occupied, frame_id=frame_id
        )

    # ---------------------------------------------------------------- file I/O
    @classmethod
    def from_image(
        cls,
        image_path,
        resolution: float,
        origin=(0.0, 0.0, 0.0),
        *,
        negate: bool = False,
        occupied_thresh: float = 0.65,
        free_thresh: float = 0.196,
        mode: str = "trinary",
        unknown_is_occupied: bool = True,
    ) -> OccupancyGrid:
        """Read a map_server image (PGM/PNG): p = (255 - v) / 255 (or v / 255 when negated)."""
        from PIL import Image

        with Image.open(image_path) as img:
            pixels = np.asarray(img.convert("L") if img.mode not in ("L", "I", "I;16") else img, dtype=float)
        if pixels.size == 0:
            raise ValueError(f"map image {image_path} is empty")
        p = pixels / 255.0 if negate else (255.0 - pixels) / 255.0
        if mode not in ("trinary", "scale", "raw"):
            raise ValueError(f"map mode must be trinary, scale or raw, got {mode!r}")
        if mode == "raw":
            occupied, unknown = pixels >= 65, (pixels < 0) | (pixels > 100)
        else:
            occupied = p > occupied_thresh
            unknown = ~occupied & ~(p < free_thresh)
        # Image row 0 is the top of the map; grid row 0 is at the origin (bottom).
        return cls(np.flipud(occupied), resolution, origin, np.flipud(unknown), unknown_is_occupied)

    @classmethod
    def from_yaml(cls, yaml_path, *, unknown_is_occupied: bool = True) -> OccupancyGrid:
        """Load a ROS map_server map (YAML + image)."""
        yaml_path = Path(yaml_path)
        with open(yaml_path) as f:
            info = yaml.safe_load(f)
        if not isinstance(info, dict):
            raise ValueError(f"{yaml_path}: not a map_server YAML mapping")
        for key in ("image", "resolution", "origin"):
            if key not in info:
                raise ValueError(f"{yaml_path}: missing key {key!r}")
        image = Path(info["image"])
        if not image.is_absolute():
            image = yaml_path.parent / image
        grid = cls.from_image(
            image,
            float(info["resolution"]),
            info["origin"],
            negate=bool(int(info.get("negate", 0))),
            occupied_thresh=float(info.get("occupied_thresh", 0.65)),
            free_thresh=float(info.get("free_thresh", 0.196)),
            mode=str(info.get("mode", "trinary")),
            unknown_is_occupied=unknown_is_occupied,
        )
        grid.meta = {k: v for k, v in info.items() if k not in ("image", "resolution", "origin")}
        grid.meta["yaml_path"] = str(yaml_path)
        return grid

    def save_yaml(self, yaml_path, image_name: str | None = None) -> Path:
        """Write ``<name>.yaml`` + ``<name>.pgm`` as map_saver does (trinary, not negated)."""
        yaml_path = Path(yaml_path)
        image_name = image_name or yaml_path.with_suffix(".pgm").name
        pixels = np.full(self.shape, PGM_FREE, dtype=np.uint8)
        pixels[self.occupied] = PGM_OCCUPIED
        pixels[self.unknown] = PGM_UNKNOWN
        from PIL import Image

        Image.fromarray(np.flipud(pixels)).save(yaml_path.parent / image_name)
        info = {
            "image": image_name,
            "mode": "trinary",
            "resolution": self.resolution,
            "origin": [float(v) for v in self.origin],
            "negate": 0,
            "occupied_thresh": 0.65,
            "free_thresh": 0.196,
        }
        with open(yaml_path, "w") as f:
            yaml.safe_dump(info, f, sort_keys=False)
        return yaml_path

    @classmethod
    def from_ascii(cls, rows: list[str], resolution: float = 1.0, origin=(0.0, 0.0, 0.0)) -> OccupancyGrid:
        """Small maps for tests: text rows top to bottom, ``#``/``@``/``T`` occupied, ``?`` unknown."""
        chars = np.array([list(r) for r in rows])
        occupied = np.isin(chars, list("#@TO"))
        unknown = chars == "?"
        return cls(np.flipud(occupied), resolution, origin, np.flipud(unknown))
