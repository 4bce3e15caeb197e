"""What viser alone costs a lecture hall's drags: the floor under ``bench_challenge.py``'s drag row.

    python benchmarks/bench_viser_floor.py [--seconds 20] [--students 100]

A plain viser server (no app: no kinematics, no panels, no gate) in its own process gives each
browser its own gizmo, as a student's arm has. A hundred headless browsers in this process send
gizmo events at 10 Hz each, a thousand a second, as in the lecture-hall row. For each event, the
server answers as the mode says, computing nothing:

* ``nothing``: no answer (taking the event in: websockets, viser's decoding and dispatch);
* ``solid arm``: the six link orientations the app sends for a UR10's solid arm;
* ``arm and ghosts``: those and the eight ghosts' six batched-mesh updates, the app's twelve
  messages per drag, through the app's own cheap setters (``viser_internals.fast_updates``).

Measured: the server's CPU per event and its share of one core, and the end to end latency as
``bench_challenge.py`` measures a student's drag (``viser_client.staleness``): an event sent → the
answer that carries it (the flange link turned by the event's x), or a newer one, arriving.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import viser
import zstandard
from viser import _messages
from websockets.asyncio.client import connect

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._report import machine, process_cpu_seconds, quiet_machine, table, write_section  # noqa: E402
from ur10dev.viser_client import CAMERA, decode_frame, encode, staleness  # noqa: E402

MODES = ("nothing", "solid arm", "arm and ghosts")
RATE_HZ = 10.0


def serve(port: int, mode: str) -> None:
    """The server process: a gizmo per browser, answered as ``mode`` says."""
    from ur10teach.viser_internals.fast_updates import set_instances, set_orientations, stop_echo

    server = viser.ViserServer(port=port, verbose=False)
    vertices = np.eye(4, 3, -1, np.float32) * 0.1
    faces = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]], np.uint32)
    rng = np.random.default_rng(0)

    @server.on_client_connect
    def _(client: viser.ClientHandle) -> None:
        gizmo = client.scene.add_transform_controls("/ik_target")
        stop_echo(gizmo)
        links = [client.scene.add_frame(f"/arm/link{i}", show_axes=False) for i in range(1, 7)]
        ghosts = [client.scene.add_batched_meshes_simple(
            f"/ghosts/floor/link{i}", vertices, faces, batched_wxyzs=np.tile([1.0, 0, 0, 0], (8, 1)),
            batched_positions=np.zeros((8, 3))) for i in range(1, 7)]

        async def dragged(_: viser.TransformControlsEvent) -> None:
            if mode == MODES[0]:
                return
            wxyzs = rng.normal(size=(6, 4))
            wxyzs /= np.linalg.norm(wxyzs, axis=1, keepdims=True)
            x = gizmo.position[0]
            wxyzs[-1] = (np.cos(x), 0.0, 0.0, np.sin(x))  # the flange turned by the event's x: the answer to it
            set_orientations(links, wxyzs)
            if mode == MODES[2]:
                for ghost in ghosts:
                    set_instances(ghost, rng.normal(size=(8, 4)).astype(np.float32), rng.normal(size=(8, 3)).astype(np.float32))

        gizmo.on_update(dragged)

    print("ready", flush=True)
    while True:
        time.sleep(60)


async def student(url: str, ready: list, start: asyncio.Event, stop: asyncio.Event, sends: list, answers: list) -> None:
    """One browser: its gizmo's events at RATE_HZ, (sent, position) into ``sends``, and (arrived, [position])
    of each answer into ``answers``, as ``ur10dev.viser_client.staleness`` reads them."""
    websocket = await connect(url, subprotocols=[f"viser-v{viser.__version__}"], max_size=None, compression=None)
    await websocket.send(encode(CAMERA))
    owner: list[str] = []

    async def read() -> None:
        decompressor = zstandard.ZstdDecompressor()
        async for raw in websocket:
            now = time.perf_counter()
            messages, buffers = decode_frame(raw, decompressor)
            for message in messages:
                if message.get("type") == "TransformControlsMessage" and message.get("owner"):
                    owner.append(message["owner"])
                elif message.get("type") == "SetOrientationMessage" and message.get("name") == "/arm/link6":
                    w, _, _, z = message["wxyz"]
                    answers.append((now, np.array([[np.arctan2(z, w), 0.0, 1.0]])))

    reader = asyncio.create_task(read())
    while not owner:
        await asyncio.sleep(0.05)
    ready.append(url)
    await start.wait()
    await asyncio.sleep(np.random.default_rng().uniform(0.0, 1.0 / RATE_HZ))
    began, k = time.perf_counter(), 0
    while not stop.is_set():
        k += 1
        x = 1e-4 * (k % 10_000)
        sends.append((time.perf_counter(), (x, 0.0, 1.0)))
        await websocket.send(encode(_messages.TransformControlsUpdateMessage(
            name="/ik_target", wxyz=(1.0, 0.0, 0.0, 0.0), position=(x, 0.0, 1.0), owner=owner[0])))
        await asyncio.sleep(max(0.0, began + k / RATE_HZ - time.perf_counter()))
    await asyncio.sleep(1.0)  # the last answers
    reader.cancel()
    await websocket.close()


async def load(url: str, pid: int, count: int, seconds: float) -> dict:
    start, stop = asyncio.Event(), asyncio.Event()
    logs, ready = [([], []) for _ in range(count)], []
    tasks = [asyncio.create_task(student(url, ready, start, stop, *log)) for log in logs]
    while len(ready) < count:  # every browser connected and its gizmo drawn
        await asyncio.sleep(0.1)
    start.set()
    await asyncio.sleep(3.0)
    events0, cpu0, t0 = sum(len(s) for s, _ in logs), process_cpu_seconds(pid), time.perf_counter()
    await asyncio.sleep(seconds)
    events1, cpu1, t1 = sum(len(s) for s, _ in logs), process_cpu_seconds(pid), time.perf_counter()
    stop.set()
    await asyncio.gather(*tasks)
    found = [v for sends, answers in logs if answers
             for (sent, _), v in zip(sends, staleness(sends, answers)) if v is not None and t0 <= sent <= t1]
    return {"rate": (events1 - events0) / (t1 - t0), "core": (cpu1 - cpu0) / (t1 - t0),
            "per_event_ms": 1e3 * (cpu1 - cpu0) / max(1, events1 - events0),
            "latency_ms": np.percentile(found, [50, 99]) * 1e3 if found else None}


def run(mode: str, count: int, seconds: float) -> dict:
    with socket.socket() as probe:  # a free port
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    server = subprocess.Popen([sys.executable, __file__, "--serve", str(port), mode], stdout=subprocess.PIPE, text=True,
                              env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parent.parent)})
    try:
        assert server.stdout is not None
        for line in server.stdout:  # viser's banner first
            if line.strip() == "ready":
                break
        else:
            raise RuntimeError("the server did not start")
        return asyncio.run(load(f"ws://127.0.0.1:{port}", server.pid, count, seconds))
    finally:
        server.kill()
        server.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="measured time per mode")
    parser.add_argument("--students", type=int, default=100)
    parser.add_argument("--print-only", action="store_true", help="print the table; BENCHMARKS.md is left as it is")
    parser.add_argument("--serve", nargs=2, metavar=("PORT", "MODE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serve:
        serve(int(args.serve[0]), args.serve[1])
        return
    rows = []
    for mode in MODES:
        quiet_machine()
        result = run(mode, args.students, args.seconds)
        latency = result["latency_ms"]
        rows.append([mode, f"{result['rate']:.0f}", f"{result['per_event_ms']:.2f} ms", f"{100 * result['core']:.0f} %",
                     "—" if latency is None else f"{latency[0]:.0f} / {latency[1]:.0f} ms"])
        print(rows[-1], flush=True)
    body = "\n".join([
        "## What viser alone costs the lecture hall's drags (`benchmarks/bench_viser_floor.py`)",
        "",
        f"Run: {machine()}. A plain viser server, no app, in its own process: each of {args.students} headless "
        f"browsers in this one has its own gizmo and sends it {RATE_HZ:.0f} events a second; the server answers "
        f"each as the mode says and computes nothing. {args.seconds:.0f} s measured per mode, one mode after the "
        "other. The floor under the drag row of *a class challenge in a lecture hall*.",
        "",
        table(["server's answer to each event", "events a second", "server CPU per event",
               "server CPU (% of one core)", "event → its answer arrived, p50 / p99"], rows),
    ])
    print(body)
    if not args.print_only:
        write_section("viser_floor", body)


if __name__ == "__main__":
    main()
