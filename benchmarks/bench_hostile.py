"""One hostile client beside a normal student: what it costs the server and the student.

    python benchmarks/bench_hostile.py

The app runs in its own process (``ur10dev/app_process.py``). A student drags the IK
target at 20 Hz for the whole run while another client, once the drag is under way:

* sends one 10 MB message (10 million empty msgpack arrays: decoded, the security review
  measured +710 MiB and a 3.7 s freeze of every student, before the gate);
* or floods 1000 slider updates as fast as its socket takes them (20 000 made other
  students' clicks take 8.5 s before the gate);
* or sends nothing (the reference).

Reported per scenario: the student's end-to-end latency (a drag event sent → the 3D
update showing it), the server's event-loop lag and drag handler, and its resident
memory before the attack and at the end.
"""

from __future__ import annotations

import asyncio
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._report import machine, quiet_machine, table, write_section  # noqa: E402
from benchmarks.bench_drag import HOME_ROTATION, loop_path  # noqa: E402
from ur10dev.app_process import running_app  # noqa: E402
from ur10dev.viser_client import ViserClient, encode, wxyz_of  # noqa: E402
from viser import _messages as messages  # noqa: E402

SECONDS = 12.0
ATTACK_AT = 3.0
BOMB = b"\xdd" + (10_000_000).to_bytes(4, "big") + b"\x90" * 10_000_000


async def attack(url: str, kind: str) -> dict:
    if kind == "none":
        return {}
    attacker = await ViserClient(url).connect()
    await asyncio.sleep(ATTACK_AT)
    started = time.perf_counter()
    if kind == "10 MB message":
        try:
            await attacker.send_raw(BOMB)
        except Exception:  # the server may hang up while the frame is still going out
            pass
        while attacker._websocket.close_code is None and time.perf_counter() - started < 30:
            await asyncio.sleep(0.01)
        return {"closed_ms": (time.perf_counter() - started) * 1e3, "close_code": attacker._websocket.close_code}
    uuid = attacker.gui["θ2 shoulder"]["uuid"]
    frames = [encode(messages.GuiUpdateMessage(uuid, {"value": float(k % 90)})) for k in range(1000)]
    for frame in frames:
        await attacker.send_raw(frame)
    sent_ms = (time.perf_counter() - started) * 1e3
    await asyncio.sleep(SECONDS - ATTACK_AT - sent_ms / 1e3 - 1)
    await attacker.close()
    return {"sent_ms": sent_ms}


async def student(url: str) -> list[float]:
    client = await ViserClient(url).connect()
    T0 = np.eye(4)
    T0[:3, :3] = HOME_ROTATION
    T0[:3, 3] = client.received.flange_updates[-1][1]
    path = loop_path(T0, int(SECONDS * 20))
    sends, start = [], time.perf_counter()
    for k, T in enumerate(path):
        sends.append((await client.drag_target(T[:3, 3], wxyz_of(T), "start" if k == 0 else "update"), T[:3, 3]))
        await asyncio.sleep(max(0.0, start + (k + 1) / 20 - time.perf_counter()))
    await asyncio.sleep(1.0)
    latencies = [v for v in client.latencies(sends) if v is not None]
    await client.close()
    return latencies


async def scenario(app, kind: str) -> dict:
    before = app.metrics(time.time())
    latencies, attacked = await asyncio.gather(student(app.url), attack(app.url, kind))
    after = app.metrics(time.time())
    return {"kind": kind, "latency": np.array(latencies) * 1e3, "before": before, "after": after, **attacked}


def main() -> None:
    rows = []
    for kind in ("none", "10 MB message", "1000-message flood"):
        quiet_machine(max_wait=300.0)
        with running_app() as app:
            result = asyncio.run(scenario(app, kind))
        latency, after, before = result["latency"], result["after"], result["before"]
        lag = after["latency"].get("event_loop_lag", {})
        what = {"none": "—", "10 MB message": f"closed (code {result.get('close_code')}) "
                f"{result.get('closed_ms', float('nan')):.0f} ms after it began to send",
                "1000-message flood": f"sent in {result.get('sent_ms', float('nan')):.0f} ms"}[kind]
        rows.append([
            kind, what,
            f"{np.percentile(latency, 50):.0f} / {np.percentile(latency, 99):.0f} / {latency.max():.0f} ms",
            f"{lag.get('p99_ms', float('nan')):.0f} / {lag.get('max_ms', float('nan')):.0f} ms",
            f"{before['rss_bytes'] / 2**20:.0f} → {after['rss_bytes'] / 2**20:.0f} MiB",
        ])
        print(rows[-1], flush=True)
    body = "\n".join([
        "## Hostile client (`benchmarks/bench_hostile.py`)",
        "",
        f"Run: {machine()}. The app in its own process; a student drags at 20 Hz for {SECONDS:.0f} s while another "
        f"client, {ATTACK_AT:.0f} s in, sends one 10 MB message (10 million empty msgpack arrays) or 1000 slider "
        "updates as fast as its socket takes them. Before the gate (`app/gate.py`) the security review measured, "
        "for the 10 MB message, +710 MiB and a 3.7 s freeze of every student, and for 20 000 slider updates, "
        "other students' clicks taking 8.5 s.",
        "",
        table(["attack", "what became of it", "the student's end to end p50 / p99 / max",
               "event-loop lag p99 / max", "server RSS: before → at the end"], rows),
    ])
    write_section("hostile", body)
    print(body)


if __name__ == "__main__":
    main()
