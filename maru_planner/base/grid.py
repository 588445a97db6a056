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
- ``grid.distance_field(d)``: the same exact distances (metres) as an array, ``inf`` beyond ``d``
  (the cost layer of ``costmap.py`` is made from it).
- ``OccupancyGrid.from_yaml(path)``, ``grid.save_yaml(path)``,
  ``OccupancyGrid(occupied, resolution, origin)``.

Maps over ``budget.MAX_MAP_CELLS`` are refused (TooLarge) before their pixels are decoded;
malformed files raise InvalidMap naming the file and the key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from PIL import Image, UnidentifiedImageError
from scipy import ndimage

from maru_planner.base.budget import Deadline, check_map_cells, unlimited
from maru_planner.errors import InvalidMap, InvalidRequest, excerpt

# Inflation works on strips of this many rows (plus the radius on each side), checking the deadline between.
_INFLATE_STRIP_ROWS = 128

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
            raise InvalidMap(f"occupied must be a 2-D array (height, width), got shape {occupied.shape}")
        check_map_cells(*occupied.shape, "map")
        self.occupied = occupied.astype(bool, copy=True)
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise InvalidMap(f"resolution must be a positive number of metres per cell, got {self.resolution}")
        self.resolution = float(self.resolution)
        try:
            origin = tuple(float(v) for v in self.origin)
        except (TypeError, ValueError):
            raise InvalidMap(f"origin must be finite (x, y, yaw), got {str(self.origin)[:60]}") from None
        if len(origin) == 2:
            origin = (*origin, 0.0)
        if len(origin) != 3 or not all(math.isfinite(v) for v in origin):
            raise InvalidMap(f"origin must be finite (x, y, yaw), got {self.origin}")
        self.origin = origin
        if self.unknown is None:
            self.unknown = np.zeros_like(self.occupied)
        else:
            self.unknown = np.asarray(self.unknown, dtype=bool)
            if self.unknown.shape != self.occupied.shape:
                raise InvalidMap(f"unknown has shape {self.unknown.shape}, occupied has {self.occupied.shape}")
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

    # --------------------------------------------------------------- inflation
    def inflate(self, radius: float, deadline: Deadline | None = None) -> OccupancyGrid:
        """Obstacles grown by a disc of ``radius`` metres (inclusive, exact to the cell).

        Computed in strips of rows, each with the obstacles within ``radius`` around it (farther
        ones cannot reach), so ``deadline`` is checked between strips.
        """
        grown = np.zeros(self.shape, dtype=bool)
        limit = radius + 1e-9 * self.resolution
        for top, bottom, distance in self._strip_distances(radius, "inflating the map", deadline):
            grown[top:bottom] = distance <= limit
        return self.with_occupied(grown)

    def distance_field(self, max_distance: float, deadline: Deadline | None = None) -> np.ndarray:
        """Exact distance (m, float64) from each cell centre to the nearest occupied cell centre, where it is at
        most ``max_distance`` (+1e-9 cell); ``inf`` farther out. Strips and deadline as :meth:`inflate`."""
        field = np.full(self.shape, np.inf)
        limit = max_distance + 1e-9 * self.resolution
        for top, bottom, distance in self._strip_distances(max_distance, "computing the cost map", deadline):
            field[top:bottom] = np.where(distance <= limit, distance, np.inf)
        return field

    def _strip_distances(self, radius: float, what: str, deadline: Deadline | None):
        """(top, bottom, distances of rows top..bottom) for every strip with an obstacle within ``radius``."""
        if not (math.isfinite(radius) and radius >= 0):
            raise InvalidRequest(f"inflation radius must be finite and >= 0, got {radius}")
        deadline = deadline or unlimited()
        reach = int(math.ceil(radius / self.resolution)) + 1
        for top in range(0, self.height, _INFLATE_STRIP_ROWS):
            deadline.check_now(what)
            bottom = min(top + _INFLATE_STRIP_ROWS, self.height)
            lo, hi = max(top - reach, 0), min(bottom + reach, self.height)
            window = self.occupied[lo:hi]
            if window.any():
                distance = ndimage.distance_transform_edt(~window) * self.resolution
                yield top, bottom, distance[top - lo : bottom - lo]

    def with_occupied(self, occupied: np.ndarray) -> OccupancyGrid:
        """Same geometry, different occupancy (unknown cells carried over as information only)."""
        unknown = None if self.unknown is None else self.unknown.copy()
        return OccupancyGrid(occupied, self.resolution, self.origin, unknown, False, self.frame_id, dict(self.meta))

    # ---------------------------------------------------------- int8 values
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
            raise InvalidMap(f"map is empty ({width} x {height} cells)")
        check_map_cells(height, width, "map")
        data = np.asarray(values, dtype=np.int16).ravel()
        if data.size != width * height:
            raise InvalidMap(f"map data has {data.size} values, width x height = {width} x {height} = {width * height}")
        cells = data.reshape(height, width)
        return cls(cells >= occupied_threshold, resolution, origin, cells < 0, unknown_is_occupied, frame_id=frame_id)

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
        """Read a map_server image (PGM/PNG): p = (255 - v) / 255 (or v / 255 when negated).

        The image size is checked against MAX_MAP_CELLS before its pixels are decoded.
        """
        if mode not in ("trinary", "scale", "raw"):
            raise InvalidMap(f"map mode must be trinary, scale or raw, got {str(mode)[:40]!r}")
        for name, value in (("occupied_thresh", occupied_thresh), ("free_thresh", free_thresh)):
            if not 0.0 <= value <= 1.0:
                raise InvalidMap(f"{name} must be in [0, 1], got {value}")
        if free_thresh > occupied_thresh:
            raise InvalidMap(f"free_thresh ({free_thresh}) must not exceed occupied_thresh ({occupied_thresh})")
        try:
            with Image.open(image_path) as img:
                width, height = img.size
                check_map_cells(height, width, f"map image {image_path}")
                pixels = np.asarray(img.convert("L") if img.mode not in ("L", "I", "I;16") else img, dtype=float)
        except (UnidentifiedImageError, Image.DecompressionBombError) as exc:
            raise InvalidMap(f"map image {image_path}: {exc}") from None
        except OSError as exc:  # missing, unreadable, or a name the file system refuses: quote an excerpt only
            reason = exc.strerror or type(exc).__name__
            raise InvalidMap(f"map image {excerpt(str(image_path), tail=True)}: {reason}") from None
        if pixels.size == 0:
            raise InvalidMap(f"map image {image_path} is empty")
        p = pixels / 255.0 if negate else (255.0 - pixels) / 255.0
        if mode == "raw":
            occupied, unknown = pixels >= 65, (pixels < 0) | (pixels > 100)
        else:
            occupied = p > occupied_thresh
            unknown = ~occupied & ~(p < free_thresh)
        # Image row 0 is the top of the map; grid row 0 is at the origin (bottom).
        return cls(np.flipud(occupied), resolution, origin, np.flipud(unknown), unknown_is_occupied)

    @classmethod
    def from_yaml(cls, yaml_path, *, unknown_is_occupied: bool = True) -> OccupancyGrid:
        """Load a ROS map_server map (YAML + image); InvalidMap naming the file and key when malformed."""
        yaml_path = Path(yaml_path)
        with open(yaml_path) as f:
            try:
                info = yaml.safe_load(f)
            except yaml.YAMLError as exc:
                where = getattr(exc, "problem_mark", None)
                line = f" (line {where.line + 1})" if where is not None else ""
                raise InvalidMap(f"{yaml_path}: not valid YAML{line}") from None
        if not isinstance(info, dict):
            raise InvalidMap(f"{yaml_path}: not a map_server YAML mapping")
        for key in ("image", "resolution", "origin"):
            if key not in info:
                raise InvalidMap(f"{yaml_path}: missing key {key!r}")
        image = Path(str(info["image"]))
        if not image.is_absolute():
            image = yaml_path.parent / image
        try:
            grid = cls.from_image(
                image,
                _number(info, "resolution", None),
                info["origin"] if isinstance(info["origin"], list | tuple) else (),
                negate=bool(_number(info, "negate", 0)),
                occupied_thresh=_number(info, "occupied_thresh", 0.65),
                free_thresh=_number(info, "free_thresh", 0.196),
                mode=str(info.get("mode", "trinary")),
                unknown_is_occupied=unknown_is_occupied,
            )
        except (InvalidMap, TypeError, ValueError) as exc:
            raise InvalidMap(f"{yaml_path}: {exc}") from None
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


def _number(info: dict, key: str, default: float | None) -> float:
    """info[key] as a finite float (``default`` when absent); InvalidMap naming the key otherwise."""
    value = info.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InvalidMap(f"{key} must be a finite number, got {str(value)[:40]}")
    return float(value)
