"""The IK-target drag handler, server side, and what one drag update costs on the wire.

    python benchmarks/bench_drag.py              # singularity overlay on
    python benchmarks/bench_drag.py --map        # and the branch-count map too (its own section)
    python benchmarks/bench_drag.py --jacobian   # and the ellipsoids, force arrow and torque bars (its own section)

Starts the app in its own process (``ur10dev/app_process.py``), connects one headless client
(``ur10dev/viser_client.py``: the messages a browser sends), switches the singularity overlay on
and drags the IK target at 20 Hz along a loop around the flange, as a student would.
Reports

* the server-side drag handler time (IK, nearest branch, snapshot, solid arm, ghost
  poses, overlay geometry: everything from the gizmo event to the queued 3D redraw), as
  the app measures it (``ur10teach.serving.metrics``); target p99 ≤ 5 ms;
* the side-panel redraw the handler asks for (at most ten a second, off the drag path);
* the bytes the client receives per update, in total and for the ghost arms alone;
* the time from sending a gizmo event to receiving the moved branches (end to end).
"""

from __future__ import annotations

import asyncio
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._report import (  # noqa: E402
    cpu_ticks,
    machine,
    quiet_machine,
    steady_cpu,
    stolen_share,
    table,
    write_section,
)
from ur10dev.app_process import running_app  # noqa: E402
from ur10dev.viser_client import ViserClient, wxyz_of  # noqa: E402
from ur10core import Arm  # noqa: E402

#: The app starts on the course's arbitrary pose; the drag keeps its orientation.
HOME_ROTATION = Arm.preset("course").fk(np.radians([30, 45, 26, 50, 60, 80]))[:3, :3]

UPDATES = 600
RATE_HZ = 20.0


def loop_path(T0: np.ndarray, n: int) -> list[np.ndarray]:
    """A loop of radius 15 cm around the start, tilting the tool ±20° as it goes."""
    path = []
    for k in range(n):
        phase = 2 * np.pi * k / 200
        T = T0.copy()
        T[:3, 3] += 0.15 * np.array([np.cos(phase) - 1, np.sin(phase), 0.3 * np.sin(2 * phase)])
        tilt = np.radians(20) * np.sin(phase)
        c, s = np.cos(tilt), np.sin(tilt)
        T[:3, :3] = T0[:3, :3] @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
        path.append(T)
    return path


async def drive(url: str, map_on: bool = False, jacobian: bool = False) -> dict:
    client = await ViserClient(url).connect()
    await client.set_gui("Show singularity overlay", True)
    if map_on:  # 40 000 IK poses each time the target moves, at the panel's pace, on the map's own thread
        await client.set_gui("Show branch-count map", True)
    if jacobian:  # the ellipsoids and the force arrow on the drag path, the torque bars at the panel's pace
        await asyncio.sleep(0.1)
        await client.set_gui("Show at the tool", True)
        await asyncio.sleep(0.1)
        await client.set_gui("Show the torques", True)
    await asyncio.sleep(0.5)
    start_flange = client.received.flange_updates[-1][1]
    T0 = np.eye(4)
    T0[:3, :3] = HOME_ROTATION
    T0[:3, 3] = start_flange
    path = loop_path(T0, UPDATES)
    start_bytes, start = client.received.bytes, time.perf_counter()
    sends = []
    for k, T in enumerate(path):
        phase = "start" if k == 0 else ("end" if k == len(path) - 1 else "update")
        sends.append((await client.drag_target(T[:3, 3], wxyz_of(T), phase), T[:3, 3]))
        await asyncio.sleep(max(0.0, start + (k + 1) / RATE_HZ - time.perf_counter()))
    await asyncio.sleep(1.0)
    total_bytes = client.received.bytes - start_bytes
    latencies = [x for x in client.latencies(sends) if x is not None]
    await client.close()
    return {
        "bytes_per_update": total_bytes / len(path),
        "end_to_end_ms": (np.percentile(latencies, 50) * 1e3, np.percentile(latencies, 99) * 1e3),
        "answered": len(latencies),
    }


def ghost_update_bytes() -> float:
    """Bytes of the ghost-arm arrays in one update: 6 links x (wxyzs, positions) of 8 instances (float32)."""
    return 6 * (8 * 4 * 4 + 8 * 3 * 4)


#: Sessions per backend, alternating between the backends so that both see the same host.
SESSIONS = 3


def run(backend: str, map_on: bool = False, jacobian: bool = False) -> tuple[dict, dict, float, tuple[float, float]]:
    """One drag session against the app on ``backend``.

    Returns the client-side result, the app's report, the host's steal during the session
    and the machine's floor (:func:`work_unit_floor`: p50, p99 ms) measured just before it,
    once the machine has settled (:func:`steady_cpu`, at most 5 minutes).
    """
    quiet_machine(max_wait=300.0)
    p50, p99, _ = steady_cpu(max_wait=300.0)
    with running_app(env={"UR10CORE_BACKEND": backend}) as app:
        before = cpu_ticks()
        result = asyncio.run(drive(app.url, map_on, jacobian))
        stolen = stolen_share(before, cpu_ticks())
        report = app.metrics(newer_than=time.time() + 0.1)
    return result, report, stolen, (p50, p99)


def main() -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--map", action="store_true", help="with the branch-count map on (section drag_map)")
    parser.add_argument("--jacobian", action="store_true",
                        help="with the ellipsoids, force arrow and torque bars on (section drag_jacobian)")
    arguments = parser.parse_args()
    map_on, jacobian = arguments.map, arguments.jacobian
    sessions: dict[str, list] = {"compiled": [], "numpy": []}
    for _ in range(SESSIONS):
        for backend in sessions:
            sessions[backend].append(run(backend, map_on, jacobian))
    ghost = ghost_update_bytes()
    rows = []
    for backend, runs in sessions.items():
        runs.sort(key=lambda run: run[1]["latency"]["drag_cpu"]["p99_ms"])
        result, report, stolen, floor = runs[len(runs) // 2]  # the median session by handler p99
        cpu, wall, panel = (report["latency"][kind] for kind in ("drag_cpu", "drag", "panel"))
        spread = ", ".join(f"{run[1]['latency']['drag_cpu']['p99_ms']:.2f}" for run in runs)
        wall_spread = ", ".join(f"{run[1]['latency']['drag']['p99_ms']:.2f}" for run in runs)
        rows += [
            [f"**{backend} backend**: drag handler, server side, CPU time (IK, nearest branch, solid arm, 8 ghosts, "
             "overlay geometry)",
             f"p50 {cpu['p50_ms']:.2f} ms, p99 {cpu['p99_ms']:.2f} ms, max {cpu['max_ms']:.2f} ms "
             f"(p99 of the {len(runs)} sessions: {spread} ms)",
             "p99 ≤ 5 ms", "PASS" if cpu["p99_ms"] <= 5 else "FAIL"],
            [f"{backend}: the same, wall time (also the time the OS ran the load generator on these two cores)",
             f"p50 {wall['p50_ms']:.2f} ms, p99 {wall['p99_ms']:.2f} ms, max {wall['max_ms']:.2f} ms "
             f"(p99 of the sessions: {wall_spread} ms; host steal {100 * stolen:.0f} %)", "—", "—"],
            [f"{backend}: the machine's floor just before that session: one fixed piece of pure-Python work, "
             "thread CPU time", f"p50 {floor[0]:.2f} ms, p99 {floor[1]:.2f} ms", "—", "—"],
            [f"{backend}: side-panel redraw, ≤ 10 per second off the drag path (sliders, tables, gauges, plot)",
             f"p50 {panel['p50_ms']:.2f} ms, p99 {panel['p99_ms']:.2f} ms", "—", "—"],
            [f"{backend}: gizmo event → moved arm received (loopback, one client, separate processes)",
             f"p50 {result['end_to_end_ms'][0]:.1f} ms, p99 {result['end_to_end_ms'][1]:.1f} ms", "—", "—"],
        ]
    result, report, _, _ = sessions["compiled"][len(sessions["compiled"]) // 2]
    rows += [
        ["bytes sent per drag update (3D at 20 Hz + panel at ≤ 10 Hz, overlay on; compiled backend)",
         f"{result['bytes_per_update'] / 1024:.1f} KiB", "a few KB", "PASS" if result["bytes_per_update"] < 8192 else "FAIL"],
        ["of which ghost-arm instance poses (6 moving links × 8 instances)", f"{ghost / 1024:.1f} KiB of arrays",
         "a few KB", "PASS" if ghost < 4096 else "FAIL"],
    ]
    handler = report["latency"]["drag"]
    numpy_cpu = sorted(run[1]["latency"]["drag_cpu"]["p50_ms"] for run in sessions["numpy"])[SESSIONS // 2]
    compiled_cpu = sorted(run[1]["latency"]["drag_cpu"]["p50_ms"] for run in sessions["compiled"])[SESSIONS // 2]
    body = "\n".join(
        [
            "## Drag handler with the branch-count map on (`benchmarks/bench_drag.py --map`)" if map_on
            else "## Drag handler with the ellipsoids and torque bars on (`benchmarks/bench_drag.py --jacobian`)" if jacobian
            else "## Drag handler (`benchmarks/bench_drag.py`)",
            "",
            f"Run: {machine()}. The app in its own process on each backend (`UR10CORE_BACKEND`), {SESSIONS} sessions "
            "each, alternating, each after waiting for a quiet host; each backend's median session (by handler CPU p99) "
            f"is shown. A session: {handler['count']} gizmo events at {RATE_HZ:.0f} Hz from one headless client in "
            "another process (viser's protocol, the messages a browser sends), singularity overlay on"
            f"{' and the branch-count map (40 000 IK poses per map, on its own thread, at most 10 maps a second)' if map_on else ''}"
            f"{', the manipulability ellipsoids and the force arrow (on the drag path) and the torque bars (with the panel)' if jacobian else ''}; "
            f"{result['answered']} of them answered by a 3D update (the rest folded into the next). The verdict is on the "
            "handler's CPU time, the server's own work without whatever the OS ran meanwhile on these two cores (the "
            "load generator decoding every frame, above all); the wall time is beside it. Each session starts once "
            "the machine has settled (the same fixed piece of work timing within 1.5× of its median at p99, for at "
            "most 5 minutes); that floor is shown with it, because on this shared virtual machine the tails of "
            "identical work move from minute to minute, and every handler's tail with them. The numpy backend adds "
            f"{numpy_cpu - compiled_cpu:.2f} ms of CPU time at the median.",
            "",
            table(["what", "measured", "target", "verdict"], rows),
        ]
    )
    write_section("drag_map" if map_on else "drag_jacobian" if jacobian else "drag", body)
    print(body)


if __name__ == "__main__":
    main()
