"""A class challenge in a lecture hall: one presenter and a hundred students in a reach challenge.

    python benchmarks/bench_challenge.py [--seconds 120] [--students 100]

The app runs in its own process (``--shared``); 101 headless clients (``ur10dev/viser_client.py``)
run in this one. The presenter starts *Reach the target*; every student gets their own arm and
drags its IK target at 10 Hz (each clock at a random phase), and every two seconds one more
student presses *Check my answer* (their tool is off the target: a wrong answer, one more in
the projector's groups). Measured:

* **projector's lag**: a check sent → the presenter's board showing it (its count of wrong
  answers standing reaches the number of students who have checked);
* **students' own drags**: end to end, a drag event sent → a 3D update of that student's own
  arm showing that target or a newer one (as ``bench_classroom.py``), and the server's handler;
* **memory**: the server's resident memory, flat after the warm-up (``bench_classroom.settled_growth``).

Targets (issue 31): projector at most 1 s behind, drags p99 ≤ 50 ms, memory flat.
"""

from __future__ import annotations

import argparse
import asyncio
import re
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._report import cpu_ticks, machine, quiet_machine, stolen_share, table, write_section  # noqa: E402
from benchmarks.bench_classroom import (  # noqa: E402
    FLAT_MIB, JOIN_CODE, TARGET_P99_MS, WARMUP_S, connect_all, drag_loop, planned_drag, sample_server, server_cpu,
    settled_growth,
)
from ur10dev.app_process import running_app  # noqa: E402
from ur10dev.viser_client import ViserClient, staleness  # noqa: E402

RATE_HZ = 10.0
CHECK_EVERY_S = 2.0
TARGET_LAG_S = 1.0
WRONG_STANDING = re.compile(r"^\| (\d+) \| ", re.M)


def wrong_standing(presenter: ViserClient) -> int:
    """How many wrong answers the projector's board counts (the sum of its groups)."""
    boards = presenter.shown("last wrong answer")
    return max((sum(int(n) for n in WRONG_STANDING.findall(board)) for board in boards), default=0)


async def check_in_turn(students: list[ViserClient], presenter: ViserClient, until: float, lags: list[float]) -> None:
    """One more student checks every CHECK_EVERY_S; how long until the projector counts them."""
    for k, student in enumerate(students):
        if time.time() + CHECK_EVERY_S > until:
            return
        sent = time.perf_counter()
        await student.set_gui("Check my answer", True)
        while wrong_standing(presenter) < k + 1:
            if time.perf_counter() - sent > 30:
                lags.append(float("inf"))
                break
            await asyncio.sleep(0.01)
        else:
            lags.append(time.perf_counter() - sent)
        await asyncio.sleep(max(0.0, sent + CHECK_EVERY_S - time.perf_counter()))


async def scenario(url: str, output: list[str], app, seconds: float, count: int) -> dict:
    idle = await asyncio.to_thread(quiet_machine)
    clients = await connect_all(url, count + 1)
    presenter, students = clients[0], clients[1:]
    code = next(JOIN_CODE.search(line).group(1) for line in output if JOIN_CODE.search(line))
    await presenter.present(code)
    await presenter.set_gui("Challenge", "Reach the target")
    started_at = time.perf_counter()
    await presenter.set_gui("Start the challenge", True)
    deadline = time.monotonic() + 300
    while any(s.gizmo_owner is None or "Check my answer" not in s.gui for s in students):
        if time.monotonic() > deadline:
            missing = [(s.gizmo_owner, "Check my answer" in s.gui) for s in students]
            raise TimeoutError(f"not every student got their own arm and the task: {missing}; the app said: {output[-30:]}")
        await asyncio.sleep(0.2)
    enlisted = time.perf_counter() - started_at
    await asyncio.sleep(2.0)
    plans = [await asyncio.to_thread(planned_drag, s, seconds, 7 * k, RATE_HZ) for k, s in enumerate(students)]
    before = await asyncio.to_thread(app.metrics, time.time())
    before["machine_ticks"] = cpu_ticks()
    samples = [before]
    sends: dict[int, list] = {id(s): [] for s in students}
    phases = np.random.default_rng(0).uniform(0.0, 1.0 / RATE_HZ, len(students))
    started = time.time()
    lags: list[float] = []
    dropped: list[str] = []
    await asyncio.gather(
        sample_server(app, started + seconds, samples, []),
        check_in_turn(students, presenter, started + seconds, lags),
        *(drag_loop(s, plans[k], sends[id(s)], phases[k], dropped, RATE_HZ) for k, s in enumerate(students)),
    )
    await asyncio.sleep(1.5)
    after = await asyncio.to_thread(app.metrics, time.time())
    after["machine_ticks"] = cpu_ticks()
    samples.append(after)
    latencies = [v for s in students for v in staleness(sends[id(s)], s.received.ghost_flanges) if v is not None]
    events = sum(len(v) for v in sends.values())
    for client in clients:
        await client.close()
    return {"enlisted": enlisted, "lags": lags, "latency_ms": np.percentile(latencies, [50, 99]) * 1e3,
            "handler": after["latency"].get("drag", {}), "samples": samples, "dropped": dropped,
            "folded": 1.0 - after["latency"].get("drag", {}).get("count", 0) / max(1, events),
            "wait": after["latency"].get("drag_wait", {}), "full_collections": after["latency"].get("gc2", {}),
            "full_during": after["latency"].get("gc2", {}).get("count", 0) - before["latency"].get("gc2", {}).get("count", 0),
            "stolen": stolen_share(before["machine_ticks"], after["machine_ticks"]), "idle_lag_ms": idle[1] * 1e3}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="drag time")
    parser.add_argument("--students", type=int, default=100)
    parser.add_argument("--print-only", action="store_true", help="print the row; BENCHMARKS.md is left as it is")
    args = parser.parse_args()
    with running_app("--shared") as app:
        result = asyncio.run(scenario(app.url, app.output, app, args.seconds, args.students))
    samples = result["samples"]
    settled, end, _ = settled_growth(samples)
    lags = np.array(result["lags"])
    p50, p99 = result["latency_ms"]
    handler, gc2 = result["handler"], result["full_collections"]
    ok = {"projector": bool(len(lags)) and lags.max() <= TARGET_LAG_S, "drags": p99 <= TARGET_P99_MS,
          "memory": end - settled <= FLAT_MIB, "dropped": not result["dropped"]}
    verdict = "PASS" if all(ok.values()) else "FAIL (" + ", ".join(k for k, v in ok.items() if not v) + ")"
    row = [f"1 + {args.students}", f"{len(lags)}: median {np.median(lags):.2f} s, max {lags.max():.2f} s",
           f"{p50:.0f} / {p99:.0f} ms", f"{handler.get('p50_ms', float('nan')):.2f} / {handler.get('p99_ms', float('nan')):.2f} ms",
           f"{100 * max(0.0, result['folded']):.0f} %; {result['wait'].get('p50_ms', float('nan')):.0f} / "
           f"{result['wait'].get('p99_ms', float('nan')):.0f} ms",
           f"{result['full_during']}; longest {gc2.get('max_ms', float('nan')):.0f} ms",
           f"{result['enlisted']:.1f} s", f"{server_cpu(samples[0], samples[-1]):.0f} %", f"{settled:.0f} → {end:.0f} MiB",
           f"{100 * result['stolen']:.0f} %", verdict]
    body = "\n".join([
        "## A class challenge in a lecture hall (`benchmarks/bench_challenge.py`)",
        "",
        f"Run: {machine()}. The app with `--shared` in its own process; {args.students} students and the presenter "
        f"as headless clients in this one, on the same two cores. *Reach the target*: every student drags their own "
        f"arm's target at {RATE_HZ:.0f} Hz for {args.seconds:.0f} s, and every {CHECK_EVERY_S:.0f} s one more presses "
        "*Check my answer*. Projector's lag = a check sent → the presenter's board counting it. Targets: the "
        f"projector at most {TARGET_LAG_S:.0f} s behind, the students' drags end to end p99 ≤ {TARGET_P99_MS:.0f} ms, "
        f"memory flat (RSS at the end within {FLAT_MIB:.0f} MiB of its value {WARMUP_S:.0f} s in).",
        "",
        table(["browsers", "projector's lag (checks)", "own drags end to end p50 / p99", "drag handler p50 / p99",
               "drag events folded into a newer one; wait for the drag worker p50 / p99",
               "Python's full collections during the drags; the longest in the run",
               "every student's arm and task after Start", "server CPU (% of one core)",
               f"server RSS from {WARMUP_S:.0f} s to the end", "stolen by the host", "verdict"], [row]),
    ])
    print(body)
    if not args.print_only:
        write_section("challenge", body)


if __name__ == "__main__":
    main()
