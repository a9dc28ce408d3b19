"""Headless Chromium for the tests that open pages: finding it, screenshots, pixel masks, timing.

Pages are loaded from files with the network blocked (an unreachable proxy and no name
resolution), so a page that needed anything online would render empty.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import threading

import numpy as np
import pytest

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
WIDTH, HEIGHT = 800, 600
CAPTION_ROWS = 55  # bottom rows hold the caption

def find_browser() -> str:
    """Path of a Chromium executable, or skip the test."""
    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    pytest.skip("no Chromium found: install it with `apt-get install -y chromium` "
                "(.ci/run does so when it can)")


def screenshots(browser, tmp_path, html, fragments, budget_ms=(1000,)):
    """Render ``html`` once per URL fragment (in parallel) and return RGB arrays."""
    from PIL import Image

    procs, outs = [], []
    budgets = list(budget_ms) * len(fragments) if len(budget_ms) == 1 else list(budget_ms)
    for i, (frag, budget) in enumerate(zip(fragments, budgets)):
        out = tmp_path / f"shot{i}.png"
        cmd = [
            browser, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
            "--disable-quic", "--no-first-run", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--hide-scrollbars",
            "--proxy-server=http://127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND",
            f"--user-data-dir={tmp_path / f'profile{i}'}", f"--window-size={WIDTH},{HEIGHT}",
            f"--virtual-time-budget={budget}", f"--screenshot={out}",
            f"{html.as_uri()}#{frag}",
        ]
        procs.append(subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE))
        outs.append(out)
    images = []
    for proc, out in zip(procs, outs):
        _, err = proc.communicate(timeout=120)
        assert out.is_file(), f"Chromium wrote no screenshot: {err.decode()[-2000:]}"
        images.append(np.asarray(Image.open(out).convert("RGB")).astype(int))
    return images


def foreground(img: np.ndarray) -> np.ndarray:
    """Pixels that differ from the white background."""
    return np.abs(img - 255).sum(axis=2) > 30


def orange(img: np.ndarray) -> np.ndarray:
    """Pixels of the beams' orange (shaded)."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 150) & (r - b > 90) & (g > 0.25 * r) & (g < 0.75 * r)


def near(mask: np.ndarray, pixel, radius: int = 2) -> bool:
    """Whether ``mask`` is set within ``radius`` pixels of (column, row)."""
    c, r = int(round(pixel[0])), int(round(pixel[1]))
    return bool(mask[max(r - radius, 0): r + radius + 1, max(c - radius, 0): c + radius + 1].any())


def draw_time_ms(browser, html, profile, timeout_s: float = 120.0) -> float:
    """Milliseconds from the page's start to the first frame drawn with its scene.

    The page reports it on the console (``pinflex: scene drawn N ms``); Chromium runs in real
    time (no virtual clock), offline, and is stopped once the line is read.
    """
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", "--proxy-server=http://127.0.0.1:9",
           "--host-resolver-rules=MAP * ~NOTFOUND", f"--user-data-dir={profile}",
           "--enable-logging=stderr", "--v=0", "--remote-debugging-port=0",
           f"--window-size={WIDTH},{HEIGHT}", f"{html.as_uri()}#gui=0"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    found: list[float] = []

    def read():
        for line in proc.stderr:
            m = re.search(r"pinflex: scene drawn (\d+) ms", line)
            if m:
                found.append(float(m.group(1)))
                return

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(timeout_s)
    proc.kill()
    proc.wait()
    assert found, f"the page drew no frame of its scene within {timeout_s:.0f} s"
    return found[0]
