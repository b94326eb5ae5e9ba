"""Screenshots of a bench's report page as a browser shows it (headless Chromium), for
docs/images/report: the whole page (half size), its top, and each setup's map.

    cramlite bench --traces --out results        # what `make run` does
    python benchmarks/report_screenshots.py results [--out docs/images/report]

Needs Chromium (`apt install chromium` on Debian) and Pillow.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

WIDTH_PX, MAX_HEIGHT_PX = 1400, 40_000


def screenshot(page: Path, out: Path) -> Image.Image:
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        raise SystemExit("needs Chromium: apt install chromium")
    subprocess.run([browser, "--headless=new", "--no-sandbox", "--disable-gpu",
                    "--hide-scrollbars", f"--window-size={WIDTH_PX},{MAX_HEIGHT_PX}",
                    f"--screenshot={out}", page.resolve().as_uri()],
                   check=True, capture_output=True, timeout=300)
    image = Image.open(out).convert("RGB")
    rows = np.flatnonzero((np.asarray(image) < 250).any(axis=(1, 2)))
    return image.crop((0, 0, image.width, int(rows.max()) + 40))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("results", type=Path, help="a folder `cramlite bench` wrote")
    parser.add_argument("--out", type=Path, default=Path("docs/images/report"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        page = screenshot(args.results / "report.html", Path(tmp) / "page.png")
    half = page.resize((page.width // 2, page.height // 2), Image.LANCZOS)
    half.quantize(colors=64).save(args.out / "report-page.png", optimize=True)
    page.crop((0, 0, page.width, 1100)).quantize(colors=128).save(
        args.out / "report-top.png", optimize=True)
    for path in sorted((args.results / "report").glob("map-*.png")):
        setup = path.stem.split("-")[1]
        Image.open(path).convert("RGB").quantize(colors=96).save(
            args.out / f"map-{setup}.png", optimize=True)
    print(f"wrote {args.out}: the page ({page.width} x {page.height} px, saved at half "
          "size), its top and the maps")


if __name__ == "__main__":
    main()
