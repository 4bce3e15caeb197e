"""Frames a second the page draws in software WebGL (a laptop without a graphics driver), default and light view.

    python benchmarks/bench_light_view.py

Starts the app in its own process (``ur10dev/app_process.py``), as ``ur10-teach``, as
``ur10-teach --light``, and as ``ur10-teach`` with *Light view* ticked in the browser's View
folder (one laptop's own choice), and opens it in headless Chromium from Debian at 1024×768
with SwiftShader, the software renderer Chromium falls back on. Once the scene is complete,
the mouse turns the view for :data:`SECONDS` (viser then draws every frame anew), and the page
counts the frames drawn, each made to wait for the one before it (:data:`COUNT_FRAMES`). Target:
at least 10 frames a second in the light view (issue 30).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._report import machine, quiet_machine, table, write_section  # noqa: E402
from ur10dev.app_process import running_app  # noqa: E402
from ur10dev.browser import CONNECTED, dismiss_software_notice, launch  # noqa: E402

WINDOW = {"width": 1024, "height": 768}
SECONDS = 10.0
SETTLE_S = 5.0  #: the scene's meshes arrive and are uploaded: not counted
TARGET_FPS = 10.0
#: Counts the page's animation frames, each waited for until the renderer has finished it: software
#: WebGL renders in Chromium's GPU process, and without the wait the page ticks at the display's rate
#: while frames are dropped. Reading one pixel back at each tick (before viser's own render in it) makes
#: the next frame wait for the last one: the count is then the frames actually drawn.
COUNT_FRAMES = """(() => {
    window.__frames = 0;
    let gl = null;
    const getContext = HTMLCanvasElement.prototype.getContext;
    HTMLCanvasElement.prototype.getContext = function (type, options) {
        const context = getContext.call(this, type, options);
        if (context && (type === "webgl2" || type === "webgl") && !context.__counted) {
            gl = context;
            context.__counted = true;
            for (const name of ["drawElements", "drawArrays", "drawElementsInstanced", "drawArraysInstanced"]) {
                const draw = context[name].bind(context);
                context[name] = (...args) => { drew = true; return draw(...args); };
            }
        }
        return context;
    };
    let drew = false;
    const pixel = new Uint8Array(4);
    const frame = window.requestAnimationFrame.bind(window);
    const tick = () => {  // a frame counts once something was drawn in it (at rest viser draws about one a second)
        if (gl && drew) { gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel); window.__frames += 1; }
        drew = false;
        frame(tick);
    };
    frame(tick);
})();"""


def frames_per_second(url: str, playwright, tick_light_view: bool = False) -> float:
    browser = launch(playwright)
    try:
        page = browser.new_page(viewport=WINDOW)
        page.add_init_script(COUNT_FRAMES)
        page.goto(url)
        page.wait_for_selector(CONNECTED, state="attached", timeout=60_000)
        dismiss_software_notice(page)
        if tick_light_view:
            page.get_by_text("View", exact=True).first.click()
            page.get_by_role("checkbox", name="Light view").check()
        page.wait_for_timeout(1000 * SETTLE_S)
        dismiss_software_notice(page)
        box = page.locator("canvas").first.bounding_box()
        cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
        page.mouse.move(cx, cy)
        page.mouse.down()  # a student turning the view: every frame is drawn anew
        start, frames = time.perf_counter(), page.evaluate("window.__frames")
        k = 0
        while time.perf_counter() - start < SECONDS:
            k += 1
            page.mouse.move(cx + 120 * math.cos(k / 20), cy + 40 * math.sin(k / 20))
        drawn = page.evaluate("window.__frames") - frames
        elapsed = time.perf_counter() - start
        page.mouse.up()
        return drawn / elapsed
    finally:
        browser.close()


def main() -> None:
    from playwright.sync_api import sync_playwright

    quiet_machine(max_wait=300.0)
    rows = []
    with sync_playwright() as playwright:
        for label, args, tick in (("default view", (), False), ("light view (`--light`)", ("--light",), True),
                                  ("default, *Light view* ticked in the browser", (), True)):
            with running_app(*args) as app:
                fps = frames_per_second(app.url, playwright, tick_light_view=tick and not args)
            verdict = ("PASS" if fps >= TARGET_FPS else "FAIL") if tick else "(reference)"
            rows.append([label, f"{fps:.1f}", f"≥ {TARGET_FPS:.0f}" if tick else "—", verdict])
            print(rows[-1], flush=True)
    body = "\n".join([
        "## Frames a second without a graphics driver (`benchmarks/bench_light_view.py`)",
        "",
        f"Run: {machine()}. The app in its own process, opened in headless Chromium from Debian at "
        f"{WINDOW['width']}×{WINDOW['height']} with SwiftShader (software WebGL). Once the scene is complete the mouse "
        f"turns the view for {SECONDS:.0f} s, and the page counts the frames drawn (each waits for the last to finish, "
        "by reading a pixel back). The UR10 at its home pose with its seven ghosts. *Light view* ticked in one "
        "browser turns off its shadows and environment lighting and draws its arm as the schematic, toon-shaded; "
        "`--light` ticks it in every browser.",
        "",
        table(["view", "frames a second", "target", ""], rows),
    ])
    write_section("light_view", body)
    print(body)


if __name__ == "__main__":
    main()
