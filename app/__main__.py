"""``python -m ur10teach`` / ``ur10-teach``: start the UR10 teaching app."""

from __future__ import annotations

import argparse
import ctypes
import os
import signal
import sys
import threading
import time
import webbrowser
from pathlib import Path

#: Where class challenges' results files are saved unless ``--results`` says otherwise (``~``: the home folder, found
#: only in shared mode, since an account may have none).
RESULTS_FOLDER = Path("~", "ur10-teach-results")
#: Buffers from this size up get pages of their own, handed back to the system once freed.
MMAP_THRESHOLD = 1 << 20


def hand_back_large_buffers() -> None:
    """Fix glibc's threshold for buffers with pages of their own (a cloud, a scene queued for a
    browser that does not read), before anything is allocated.

    By default glibc raises it to 32 MiB once the first such buffer is freed; later ones then
    stay in its heap. After eight never-reading browsers had asked for clouds, the server
    kept 50–100 MiB over its baseline, against 15 MiB with the threshold fixed at start (three
    rounds each, 2026-12-02). ``UR10_TEACH_MALLOC_DEFAULTS=1`` keeps glibc's way (the
    hostile-client benchmark measures both). Elsewhere than glibc, nothing to do.
    """
    if os.environ.get("UR10_TEACH_MALLOC_DEFAULTS") == "1":
        return
    try:
        ctypes.CDLL("libc.so.6").mallopt(-3, MMAP_THRESHOLD)  # -3: M_MMAP_THRESHOLD (malloc.h)
    except (OSError, AttributeError):
        pass


hand_back_large_buffers()  # before numpy and the rest allocate

import ur10core  # noqa: E402
from ur10core import Arm  # noqa: E402
from ur10core.challenges import builtin, load, unfit  # noqa: E402

from .features.arm_picker import FIRST_ARMS  # noqa: E402
from .serving import logs  # noqa: E402


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="ur10-teach", description="Learn UR10 kinematics in the browser.")
    parser.add_argument("--host", default="127.0.0.1",
                        help="interface to listen on (default 127.0.0.1; 0.0.0.0 lets students on the network join)")
    parser.add_argument("--port", type=int, default=8080, help="port (default 8080; the next free one if busy)")
    parser.add_argument("--preset", choices=Arm.UR_PRESETS, default="course",
                        help="link lengths: the course's table, UR's CB3 UR10 or the UR10e (default course)")
    parser.add_argument("--arm", choices=FIRST_ARMS, default="ur10",
                        help="the arm every browser opens on: the app's UR10 (default) or one of the course's other "
                             "arms; every arm stays in the picker (in shared mode, the arm the class sees first)")
    parser.add_argument("--shared", action="store_true",
                        help="shared demo mode: everyone watches the presenter's arm; this computer's own "
                             "browser presents, or the one that enters the printed join code")
    parser.add_argument("--lecture", action="store_true",
                        help="lecture mode in every browser: type of 20 px and more, thick lines (each browser "
                             "can switch it in its View folder)")
    parser.add_argument("--light", action="store_true",
                        help="the light view in every browser, for laptops without a graphics driver (software "
                             "WebGL): the schematic arm, toon-shaded, no shadows, no environment lighting; drawn several times "
                             "faster (each browser can switch it in its View folder)")
    parser.add_argument("--no-browser", action="store_true",
                        help="do not open the page in this computer's browser (it opens when the app is started in a "
                             "terminal on a desktop)")
    parser.add_argument("--allow-origin", action="append", default=[], metavar="URL",
                        help="a web page besides the app's own that may connect, e.g. http://course-site:8000 "
                             "(repeat for more; by default only the app's own page can)")
    parser.add_argument("--challenges", metavar="FILE",
                        help="with --shared: the teacher's own class challenges, a TOML file (README, For teachers); "
                             "the built-in ones stay offered after them")
    parser.add_argument("--results", metavar="FOLDER", type=Path,
                        help=f"with --shared: where each class challenge's results file is saved while students check, "
                             f"as it ends and as the server stops (default {RESULTS_FOLDER})")
    args = parser.parse_args(argv)
    if args.results is not None and not args.shared:
        parser.error("--results needs --shared (the results are a class challenge's)")
    if args.shared:
        try:
            args.results = (args.results or RESULTS_FOLDER).expanduser().absolute()
        except (RuntimeError, KeyError):  # (no home folder: Python 3.12 raises where it guessed one before)
            parser.error(f"no home folder for {RESULTS_FOLDER}: name the folder for the results with --results FOLDER")
    args.challenge_list = builtin()
    if args.challenges is not None:
        if not args.shared:
            parser.error("--challenges needs --shared (challenges are set by the presenter)")
        try:
            own = load(args.challenges)
        except (OSError, ValueError) as error:
            parser.error(f"--challenges: {error}")
        for challenge in own:
            why = unfit(challenge, args.preset)
            if why:
                parser.error(f"--challenges: {challenge.title!r} on the {args.preset} preset: {why}")
        args.challenge_list = (*own, *builtin())
        titles = [c.title for c in args.challenge_list]
        if len(set(titles)) != len(titles):
            parser.error("--challenges: a challenge in the file has the title of a built-in one; give it another")
    for origin in args.allow_origin:
        if not origin.startswith(("http://", "https://")) or "/" in origin.split("://", 1)[1].rstrip("/"):
            parser.error(f"--allow-origin takes a page's origin such as http://host:8000, got {origin!r}")
    from .serving.server import listening_problem

    problem = listening_problem(args.host, args.port)
    if problem:
        parser.error(f"--host {args.host} --port {args.port}: {problem}")
    return args


def main(argv: list[str] | None = None, started=None) -> None:
    """Serve until Ctrl+C. ``started(app)`` is called once it serves (``ur10dev.metered_app`` measures it)."""
    # a console that cannot show a letter of the results folder's name (a Windows one written to a file, in its
    # code page) shows it escaped, and the app starts
    for stream in (sys.stdout, sys.stderr):
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    args = parse_args(argv)
    logs.install()
    from .serving.server import TeachingServer

    app = TeachingServer(preset=args.preset, first_arm=args.arm, host=args.host, port=args.port, shared=args.shared,
                         allowed_origins=args.allow_origin, lecture=args.lecture, light=args.light,
                         challenges=args.challenge_list, results=args.results if args.shared else None)
    moved = "" if args.port in (0, app.port) else f" (port {args.port} was busy)"
    mode = "shared demo mode" if args.shared else "every browser has its own arm"
    kernel = "compiled kernel" if ur10core.BACKEND == "compiled" else "numpy, no compiled kernel"
    print(f"\nUR10 teaching app ({args.preset}, {mode}; kinematics: {kernel}) is running{moved}. Open:", flush=True)
    for url in app.urls:
        print(f"    {url}", flush=True)
    if args.arm != "ur10":
        print(f"Browsers open on the {app.first_choice}; every arm stays in the picker.", flush=True)
    if app.everywhere:
        print("Students on the same network use one of the addresses above." if app.join_urls else
              "This computer has no network address that students could reach yet: connect it to the class's network "
              "(or start its hotspot). The console and the teacher's screen then show the address.", flush=True)
    if app.classroom is not None:
        print(f"Join code for the presenter: {app.classroom.code} (a page opened on this computer presents "
              "without it)", flush=True)
        print(f"Class challenges: {len(args.challenge_list)} (the presenter's Challenge folder); their results are "
              f"saved in {args.results}", flush=True)
    if started is not None:
        started(app)
    print("Press Ctrl+C to stop.", flush=True)
    if not args.no_browser and sys.stdout.isatty():  # a person at a terminal, not a script reading the output
        open_page(app.urls[0])
    signal.signal(signal.SIGTERM, _interrupt)  # stop as on Ctrl+C
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        app.stop()


def open_page(url: str) -> threading.Thread | None:
    """Open ``url`` in this computer's browser, as a student who typed the command expects, where a window can
    open: on Linux only in a desktop session (over SSH, Python's fallback is a text browser that takes the terminal
    over). On a thread of its own (returned): a browser that starts slowly, or never, does not hold the server up."""
    if sys.platform not in ("win32", "darwin") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return None
    opening = threading.Thread(target=webbrowser.open, args=(url,), name="open the page", daemon=True)
    opening.start()
    return opening


def _interrupt(signum, frame) -> None:  # noqa: ANN001
    raise KeyboardInterrupt


if __name__ == "__main__":
    main()
