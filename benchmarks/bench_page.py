"""What a student's browser downloads, and how long until it shows the arm, against another commit.

    python benchmarks/bench_page.py --against PATH     # PATH: a checkout of the reference commit

Starts the app of this checkout and of the reference, each in its own process
(``ur10dev/app_process.py``), and opens each in headless Chromium from Debian (1280×720, the
software WebGL of a laptop without a GPU driver) three times, alternating. Reports the
median run of each:

* the page weight: the HTTP responses (viser's page and client bundle, as transferred)
  plus every websocket frame the server sends until the scene is complete;
* the time from navigation to the first rendered arm: the canvas is sampled every
  ~0.1 s, and the arm counts as drawn once its dark joint caps cover half the pixels
  they cover at the end (both versions draw the caps in the same charcoal);
* the time until the last websocket frame of the initial scene.
"""

from __future__ import annotations

import argparse
import io
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._report import machine, quiet_machine, table, write_section  # noqa: E402
from ur10dev.app_process import ROOT, running_app  # noqa: E402
from ur10dev.browser import CONNECTED, launch  # noqa: E402

RUNS = 3
WINDOW = {"width": 1280, "height": 720}
CAP = np.array((70, 72, 78))  # app.style.JOINT_CAP_GREY, the same in both versions
QUIET_S = 2.0  # no websocket frame for this long: the initial scene is complete


def cap_pixels(page) -> int:
    from PIL import Image

    shot = np.asarray(Image.open(io.BytesIO(page.locator("canvas").first.screenshot())).convert("RGB"), dtype=int)
    return int((np.abs(shot - CAP).sum(axis=-1) < 40).sum())


def visit(url: str, playwright) -> dict:
    browser = launch(playwright)
    page = browser.new_page(viewport=WINDOW)
    http_bytes, ws_bytes, last_frame = [0], [0], [0.0]

    def response(resp) -> None:
        try:
            http_bytes[0] += resp.request.sizes()["responseBodySize"]
        except Exception:  # a response without a body (a redirect, a websocket upgrade)
            pass

    def frame(payload) -> None:
        ws_bytes[0] += len(payload)
        last_frame[0] = time.perf_counter()

    page.on("response", response)
    page.on("websocket", lambda ws: ws.on("framereceived", frame))
    start = time.perf_counter()
    page.goto(url)
    page.wait_for_selector(CONNECTED, state="attached", timeout=60_000)
    samples = []  # (time since navigation, cap pixels)
    while not last_frame[0] or time.perf_counter() - last_frame[0] < QUIET_S or len(samples) < 10:
        samples.append((time.perf_counter() - start, cap_pixels(page)))
        if time.perf_counter() - start > 60:
            break
    page.wait_for_timeout(1500)
    final = cap_pixels(page)
    first_arm = next((t for t, count in samples if count >= 0.5 * final), float("nan"))
    browser.close()
    return {"http": http_bytes[0], "ws": ws_bytes[0], "first_arm_s": first_arm,
            "scene_s": last_frame[0] - start, "cap_pixels": final}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", type=Path, required=True, help="a checkout of the reference commit")
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    commits = {}
    for root in (ROOT, args.against):
        commits[root] = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True,
                                       text=True).stdout.strip()
    runs: dict[Path, list[dict]] = {ROOT: [], args.against: []}
    quiet_machine(max_wait=300.0)
    with sync_playwright() as playwright:
        for _ in range(RUNS):
            for root in runs:
                with running_app(root=root) as app:
                    time.sleep(1.0)
                    runs[root].append(visit(app.url, playwright))
    rows = []
    for root, label in ((args.against, f"reference {commits[args.against]} (schematic arm only)"),
                        (ROOT, f"this checkout {commits[ROOT]} (UR's UR10 meshes, the schematic beside them)")):
        results = sorted(runs[root], key=lambda r: r["first_arm_s"])
        median = results[len(results) // 2]
        weight = (median["http"] + median["ws"]) / 2**20
        spread = ", ".join(f"{r['first_arm_s']:.2f}" for r in results)
        rows.append([label, f"{weight:.2f} MiB ({median['http'] / 2**20:.2f} page + {median['ws'] / 2**20:.2f} "
                            "websocket)",
                     f"{median['first_arm_s']:.2f} s (runs: {spread})",
                     f"{median['scene_s']:.2f} s"])
    body = "\n".join([
        "## Page weight and time to the first rendered arm (`benchmarks/bench_page.py`)",
        "",
        f"Run: {machine()}. Each app in its own process, opened {RUNS} times in headless Chromium from Debian "
        f"({WINDOW['width']}×{WINDOW['height']}, software WebGL), alternating between the two; the median run by "
        "time to first arm is shown. Page weight: HTTP responses as transferred plus every websocket frame until "
        f"{QUIET_S:.0f} s pass without one. First arm: the canvas sampled about every 0.1 s until the joint caps "
        "cover half their final pixels.",
        "",
        table(["version", "page weight", "navigation → first rendered arm", "→ last frame of the initial scene"], rows),
    ])
    write_section("page", body)
    print(body)


if __name__ == "__main__":
    main()
