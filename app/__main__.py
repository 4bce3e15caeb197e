"""``python -m app`` / ``ur10-teach``: start the UR10 teaching app."""

from __future__ import annotations

import argparse
import logging
import signal
import time

from ur10core import Arm

from .processes import MAX_PROCESSES, Helpers, can_share_a_socket, default_process_count, serve_balanced


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="ur10-teach", description="Learn UR10 kinematics in the browser.")
    parser.add_argument("--host", default="127.0.0.1",
                        help="interface to listen on (default 127.0.0.1; 0.0.0.0 lets students on the network join)")
    parser.add_argument("--port", type=int, default=8080, help="port (default 8080; the next free one if busy)")
    parser.add_argument("--preset", choices=Arm.PRESETS, default="course",
                        help="link lengths: the course's table, UR's CB3 UR10 or the UR10e (default course)")
    parser.add_argument("--shared", action="store_true",
                        help="shared demo mode: everyone watches the presenter's arm; the browser that enters "
                             "the printed join code presents")
    parser.add_argument("--processes", type=int, default=None, metavar="N",
                        help="serve from N processes on the one port (default: one per core, at most "
                             f"{MAX_PROCESSES}, when serving the network in independent mode; otherwise 1)")
    args = parser.parse_args(argv)
    if args.processes is None:
        args.processes = default_process_count(args.host, args.shared)
    elif args.processes < 1:
        parser.error("--processes must be at least 1")
    elif args.processes > 1 and args.shared:
        parser.error("--shared runs in one process (everyone watches one arm): leave out --processes")
    elif args.processes > 1 and not can_share_a_socket():
        parser.error("--processes above 1 needs a POSIX system (Linux, macOS)")
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    from .server import TeachingServer

    helpers = None
    if args.processes > 1:
        listener = serve_balanced(args.host, args.port, args.processes)
        app = TeachingServer(preset=args.preset, host=args.host, listener=listener)
        try:
            helpers = Helpers(listener, preset=args.preset, host=args.host)
        except RuntimeError as exc:
            app.stop()
            raise SystemExit(f"{exc}; --processes 1 serves from this process alone") from None
    else:
        app = TeachingServer(preset=args.preset, host=args.host, port=args.port, shared=args.shared)
    moved = "" if args.port in (0, app.port) else f" (port {args.port} was busy)"
    mode = "shared demo mode" if args.shared else "every browser has its own arm"
    if args.processes > 1:
        mode += f", {args.processes} processes"
    print(f"\nUR10 teaching app ({args.preset}, {mode}) is running{moved}. Open:", flush=True)
    for url in app.urls:
        print(f"    {url}", flush=True)
    if args.host in ("0.0.0.0", ""):
        print("Students on the same network use one of the addresses above.", flush=True)
    if app.classroom is not None:
        print(f"Join code for the presenter: {app.classroom.code}", flush=True)
    print("Press Ctrl+C to stop.", flush=True)
    signal.signal(signal.SIGTERM, _interrupt)  # stop as on Ctrl+C, helpers included
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        if helpers is not None:
            helpers.stop()
        app.stop()


def _interrupt(signum, frame) -> None:  # noqa: ANN001
    raise KeyboardInterrupt


if __name__ == "__main__":
    main()
