"""A headless browser on the view, for its tests and ``bench/view_latency.py``: Debian's Chromium
(``scripts/install_browser.sh``) driven by Playwright's sync API, WebGL in software (SwiftShader).

Is the robot drawn? Not "some pixels differ from the background": viser's notices and panels float over the
canvas. :func:`robot_pixels` shows the robot and hides it (the server toggles it) on a settled page: the pixels
that change are the robot's. A page shows the robot when most of those pixels look as with it, not as without it
(:func:`robot_shown`). Its screenshots come straight from Chromium's compositor over the DevTools protocol
(:class:`Screen`, ~40 ms on an idle page); Playwright's ``page.screenshot`` first waits for the page's fonts, which
makes a poll during a page's start wait ~1 s longer than the page takes to draw.
"""

from __future__ import annotations

import base64
import io
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # playwright is imported by the callers that drive a browser
    from playwright.sync_api import Browser, CDPSession, Page, Playwright

BROWSER_PATH = Path("/usr/bin/chromium")
LAUNCH_ARGS = ["--enable-unsafe-swiftshader", "--use-angle=swiftshader", "--ignore-gpu-blocklist"]
VIEWPORT = {"width": 800, "height": 600}
CHANGED = 30  # a pixel whose R+G+B differ by more than this between two images changed
SHOWN_SHARE = 0.9  # the robot is shown when this share of its pixels look as with it


def missing_reason() -> str | None:
    """Why no browser test can run here (one line), or None."""
    if not os.access(BROWSER_PATH, os.X_OK):
        return f"{BROWSER_PATH} is missing: run scripts/install_browser.sh as root (apt-get install chromium)"
    return None


def launch(playwright: Playwright) -> Browser:
    """Headless Chromium with software WebGL (``--no-sandbox`` as root, where Chromium refuses its sandbox)."""
    args = LAUNCH_ARGS + (["--no-sandbox"] if os.geteuid() == 0 else [])
    return playwright.chromium.launch(executable_path=str(BROWSER_PATH), args=args, headless=True)


def canvas_image(page: Page) -> np.ndarray:
    """The 3-D canvas as an (h, w, 3) uint8 image."""
    box = page.locator("canvas").first.bounding_box()
    clip = None if box is None else {k: box[k] for k in ("x", "y", "width", "height")}
    png = page.screenshot(clip=clip)  # type: ignore[arg-type]  # (a locator's screenshot waits for a still frame)
    return _decoded(png)


def drawn_fraction(image: np.ndarray) -> float:
    """The share of pixels that are not the image's most common colour (the background)."""
    rgb = image.reshape(-1, 3).astype(np.uint32)
    packed = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    background = np.argmax(np.bincount(packed, minlength=1 << 24))
    return float(np.mean(packed != background))


def wait_drawn(page: Page, timeout: float, fraction: float = 0.01) -> float:
    """Wait until the canvas has more than ``fraction`` of drawn pixels; the fraction (0.0 when it never did).
    Something is drawn, not necessarily the robot (viser's notice passes it): :func:`wait_shown` waits for that."""
    page.wait_for_selector("canvas", timeout=timeout * 1000.0)
    deadline = time.monotonic() + timeout
    drawn = 0.0
    while time.monotonic() < deadline:
        drawn = drawn_fraction(canvas_image(page))
        if drawn > fraction:
            return drawn
        time.sleep(0.05)
    return 0.0


def _decoded(png: bytes) -> np.ndarray:
    # lazy: Pillow decodes screenshots only here (matplotlib's dependency)
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


class Screen:
    """Screenshots of a page's viewport from Chromium's compositor (what the page shows now, without waiting for
    its fonts or a still frame as ``page.screenshot`` does). Open it before ``page.goto`` to watch a page start."""

    def __init__(self, page: Page):
        self._cdp: CDPSession = page.context.new_cdp_session(page)

    def grab(self, box: tuple[int, int, int, int] | None = None) -> np.ndarray:
        """The viewport, or its ``box`` (x, y, width, height in pixels), as an (h, w, 3) uint8 image (a page that has
        drawn nothing yet: retried)."""
        # lazy: playwright is imported by the callers that drive a browser
        from playwright.sync_api import Error

        options: dict = {"format": "png", "optimizeForSpeed": True}
        if box is not None:
            options["clip"] = dict(zip(("x", "y", "width", "height"), box), scale=1)
        deadline = time.monotonic() + 30.0
        while True:
            try:
                shot = self._cdp.send("Page.captureScreenshot", options)
                return _decoded(base64.b64decode(shot["data"]))
            except Error as exc:  # "Unable to capture screenshot": no frame yet (a page still loading)
                if "Unable to capture" not in exc.message or time.monotonic() > deadline:
                    raise
                time.sleep(0.01)

    def settled(self, timeout: float = 10.0, still: int = 3) -> np.ndarray:
        """The first image that ``still`` grabs in a row (~0.1 s apart) agree on; the last one after ``timeout``."""
        deadline = time.monotonic() + timeout
        image, same = self.grab(), 1
        while same < still and time.monotonic() < deadline:
            time.sleep(0.1)
            latest = self.grab()
            same = same + 1 if not np.any(changed(latest, image)) else 1
            image = latest
        return image


def changed(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(h, w) bool: the pixels that differ by more than CHANGED (R+G+B) between images ``a`` and ``b``."""
    return np.abs(a.astype(np.int16) - b.astype(np.int16)).sum(axis=-1) > CHANGED


@dataclass(frozen=True)
class RobotPixels:
    """A settled page's images with the robot shown and hidden, and where they differ (the robot's pixels), cut to
    the box around those pixels (a screenshot of that box costs a fraction of the viewport's)."""

    shown: np.ndarray
    hidden: np.ndarray
    mask: np.ndarray  # (h, w) bool
    box: tuple[int, int, int, int]  # x, y, width, height in the viewport
    share: float  # of the viewport


def robot_region(shown: np.ndarray, hidden: np.ndarray, mask: np.ndarray) -> RobotPixels:
    """The robot's ``mask`` (pixels of ``shown`` and ``hidden``, with and without the robot), cut to its box."""
    rows, cols = np.nonzero(mask)
    if not len(rows):
        return RobotPixels(shown, hidden, mask, (0, 0, mask.shape[1], mask.shape[0]), 0.0)
    y0, y1, x0, x1 = int(rows.min()), int(rows.max()) + 1, int(cols.min()), int(cols.max()) + 1
    cut = (slice(y0, y1), slice(x0, x1))
    return RobotPixels(shown[cut], hidden[cut], mask[cut], (x0, y0, x1 - x0, y1 - y0), float(np.mean(mask)))


def robot_pixels(screen: Screen, set_visible: Callable[[bool], None], timeout: float = 10.0) -> RobotPixels:
    """The robot's pixels on a settled page: ``set_visible(False)`` hides it, ``set_visible(True)`` shows it again.
    Pixels that change between two images with the robot (an animation, a panel's text) are not counted."""
    shown = screen.settled(timeout)
    set_visible(False)
    try:
        hidden = screen.settled(timeout)
    finally:
        set_visible(True)
    again = screen.settled(timeout)
    return robot_region(shown, hidden, changed(shown, hidden) & ~changed(shown, again))


def robot_shown(image: np.ndarray, robot: RobotPixels) -> float:
    """The share of the robot's pixels that ``image`` shows as with the robot (closer to it than to without)."""
    if not robot.mask.any() or image.shape != robot.shown.shape:
        return 0.0
    pixels = image[robot.mask].astype(np.int16)
    to_shown = np.abs(pixels - robot.shown[robot.mask]).sum(axis=-1)
    to_hidden = np.abs(pixels - robot.hidden[robot.mask]).sum(axis=-1)
    return float(np.mean(to_shown < to_hidden))


def wait_shown(screen: Screen, robot: RobotPixels, timeout: float, since: float | None = None) -> float | None:
    """Seconds from ``since`` (a ``time.monotonic()``; default now) until a screenshot (of the robot's box) shows
    SHOWN_SHARE of the robot's pixels, timed when the screenshot returned (by then the page showed it); None if
    none did within ``timeout``."""
    t0 = time.monotonic() if since is None else since
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        image = screen.grab(robot.box)
        seen = time.monotonic() - t0
        if robot_shown(image, robot) >= SHOWN_SHARE:
            return seen
    return None
