"""A headless browser on the view, for its tests and ``bench/view_latency.py``: Debian's Chromium
(``scripts/install_browser.sh``) driven by Playwright's sync API, WebGL in software (SwiftShader).
"""

from __future__ import annotations

import io
import os
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # playwright is imported by the callers that drive a browser
    from playwright.sync_api import Browser, Page, Playwright

BROWSER_PATH = Path("/usr/bin/chromium")
LAUNCH_ARGS = ["--enable-unsafe-swiftshader", "--use-angle=swiftshader", "--ignore-gpu-blocklist"]
VIEWPORT = {"width": 800, "height": 600}


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
    # lazy: Pillow decodes the screenshot only here (matplotlib's dependency)
    from PIL import Image

    box = page.locator("canvas").first.bounding_box()
    clip = None if box is None else {k: box[k] for k in ("x", "y", "width", "height")}
    png = page.screenshot(clip=clip)  # type: ignore[arg-type]  # (a locator's screenshot waits for a still frame)
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def drawn_fraction(image: np.ndarray) -> float:
    """The share of pixels that are not the image's most common colour (the background)."""
    rgb = image.reshape(-1, 3).astype(np.uint32)
    packed = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    background = np.argmax(np.bincount(packed, minlength=1 << 24))
    return float(np.mean(packed != background))


def wait_drawn(page: Page, timeout: float, fraction: float = 0.01) -> float:
    """Wait until the canvas has more than ``fraction`` of drawn pixels; the fraction (0.0 when it never did)."""
    page.wait_for_selector("canvas", timeout=timeout * 1000.0)
    deadline = time.monotonic() + timeout
    drawn = 0.0
    while time.monotonic() < deadline:
        drawn = drawn_fraction(canvas_image(page))
        if drawn > fraction:
            return drawn
        time.sleep(0.05)
    return 0.0
