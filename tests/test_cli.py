"""``python -m ur10teach``: what the teacher types and what it prints."""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from viser import _messages as messages

from ur10teach.__main__ import parse_args
from ur10teach.serving.server import TeachingServer, lan_addresses, listening_problem
from ur10dev.app_process import ROOT, running_app, serving
from ur10dev.viser_client import ViserClient
from ur10dev.waiting import HANG_TIMEOUT, until, wait_for

pytestmark = pytest.mark.server


def test_defaults_are_loopback_8080_course():
    args = parse_args([])
    assert (args.host, args.port, args.preset, args.shared) == ("127.0.0.1", 8080, "course", False)
    args = parse_args(["--host", "0.0.0.0", "--port", "9000", "--preset", "ur10e", "--shared"])
    assert (args.host, args.port, args.preset, args.shared) == ("0.0.0.0", 9000, "ur10e", True)
    assert parse_args([]).arm == "ur10" and parse_args(["--arm", "three_dof"]).arm == "three_dof"


def test_challenge_results_are_saved_in_the_users_home_unless_told_where(capsys, tmp_path, monkeypatch):
    from ur10teach.__main__ import RESULTS_FOLDER

    assert parse_args(["--shared"]).results == Path.home() / "ur10-teach-results" == RESULTS_FOLDER.expanduser()
    monkeypatch.chdir(tmp_path)
    assert parse_args(["--shared", "--results", "lesson 3"]).results == tmp_path / "lesson 3"
    with pytest.raises(SystemExit):
        parse_args(["--results", "lesson 3"])
    assert "--results needs --shared" in capsys.readouterr().err


def test_an_account_without_a_home_folder_starts_and_is_asked_for_a_results_folder_in_shared_mode(capsys, monkeypatch):
    def no_home(path):  # as Python 3.12 and later do where neither $HOME nor the user database gives one
        raise RuntimeError("Could not determine home directory.")

    monkeypatch.setattr(Path, "home", classmethod(no_home))
    monkeypatch.setattr(Path, "expanduser", no_home)
    assert parse_args([]).results is None  # (the module's import raised here before: the app did not start at all)
    with pytest.raises(SystemExit):
        parse_args(["--shared"])
    assert "no home folder for ~/ur10-teach-results: name the folder for the results with --results" in capsys.readouterr().err


def test_the_arm_to_open_on_is_one_of_the_picker(capsys):
    with pytest.raises(SystemExit):
        parse_args(["--arm", "ur10e"])  # the UR10's numbers are --preset's
    assert "argument --arm: invalid choice: 'ur10e'" in capsys.readouterr().err


@pytest.mark.parametrize("flags, words", [
    (["--port", "70000"], "the port is from 1 to 65535"),
    (["--port", "-1"], "the port is from 1 to 65535"),
    (["--host", "nosuchhost.invalid"], "the host is an address of this computer"),
    (["--host", "999.1.1.1"], "the host is an address of this computer"),
    (["--host", "192.0.2.1"], "this computer has no address 192.0.2.1"),  # (TEST-NET-1: nobody's)
])
def test_a_host_or_port_this_computer_cannot_serve_at_is_refused_at_once(flags, words, capsys):
    """viser tried a thousand ports at an address that is not this computer's (a typo, or the one it had on
    yesterday's network), then waited for ever without a word; at a name it looked each up in a DNS a classroom
    without internet may never answer; a port beyond 65535 printed a traceback and hung."""
    with pytest.raises(SystemExit):
        parse_args(flags)
    assert words in capsys.readouterr().err
    with pytest.raises(ValueError, match=words):
        TeachingServer(host=flags[1] if flags[0] == "--host" else "127.0.0.1",
                       port=int(flags[1]) if flags[0] == "--port" else 0)


def test_an_ipv6_host_is_given_as_an_address_a_browser_takes():
    if listening_problem("::1", 0):
        pytest.skip("this machine has no IPv6 loopback")
    app = TeachingServer(host="::1", port=0)
    try:
        assert app.urls == [f"http://[::1]:{app.port}"]  # ("http://::1:8080" is no address)
    finally:
        app.stop()


def test_the_ipv6_any_address_listens_on_every_interface_as_0_0_0_0_does():
    """``--host ::`` is how some write "every interface". asyncio listens on IPv6 alone there: this machine's own
    127.0.0.1 was refused, and the teacher was told to give students http://[::]:port, which no browser opens."""
    if listening_problem("::", 0):
        pytest.skip("this machine has no IPv6")
    with socket.socket(socket.AF_INET6) as probe:  # a port free in both families: at port 0 each would get its own
        probe.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 0)
        probe.bind(("::", 0))
        port = probe.getsockname()[1]
    app = TeachingServer(host="::", port=port)  # (were it taken meanwhile, the next free one)
    try:
        assert app.host == "" and app.urls[0] == f"http://127.0.0.1:{app.port}" and "[::]" not in " ".join(app.urls)
        assert app.open_to_network
        for family, address in ((socket.AF_INET, "127.0.0.1"), (socket.AF_INET6, "::1")):
            if family == socket.AF_INET6 and listening_problem("::1", 0):
                continue
            with socket.create_connection((address, app.port), timeout=HANG_TIMEOUT) as connection:
                connection.sendall(b"GET / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
                assert connection.recv(12).startswith(b"HTTP/1.1 ")
    finally:
        app.stop()


def test_a_challenge_on_the_app_s_ur10_must_fit_the_preset_it_runs(tmp_path, capsys, monkeypatch):
    """A file's challenge on "ur10" is checked again on the preset the server runs, and refused at start where
    that preset cannot be asked it; a built-in one is not offered there. The ur10e had no link masses until
    2026-12-04 (its students' gravity checks raised "no link masses for 'ur10e'"): it has UR's now, and this
    takes them away to see a challenge refused."""
    from ur10core.challenges import builtin, unfit
    from ur10core.dynamics import MASSES
    from ur10teach.serving.server import TeachingServer

    file = tmp_path / "class.toml"
    file.write_text('[[challenge]]\ntitle = "Hold it"\nkind = "numbers"\njoints = [0, 0, 0, 0, 0, 0]\n'
                    'quantity = "gravity_torque"\n')
    for preset in ("course", "ur10e"):
        assert parse_args(["--shared", "--preset", preset, "--challenges", str(file)]).challenge_list[0].title == "Hold it"
        assert not [c.title for c in builtin() if unfit(c, preset)]
    monkeypatch.delitem(MASSES, "ur10e")
    with pytest.raises(SystemExit):
        parse_args(["--shared", "--preset", "ur10e", "--challenges", str(file)])
    assert "'Hold it' on the ur10e preset: gravity_torque needs the arm's link masses" in capsys.readouterr().err
    server = TeachingServer(preset="ur10e", port=0, challenges=builtin())
    try:
        assert [c.title for c in builtin() if c not in server.challenges] == ["Holding itself up"]
    finally:
        server.stop()


def test_lan_addresses_are_real_ipv4_addresses(monkeypatch):
    for address in lan_addresses():
        assert not ipaddress.IPv4Address(address).is_loopback

    def no_interfaces():
        raise OSError(1, "Operation not permitted")

    monkeypatch.setattr(socket, "if_nameindex", no_interfaces)  # a sandbox's: the app still starts
    assert isinstance(lan_addresses(), list)


#: a network of this machine's own, as a laptop has that makes a hotspot for its class and is on no other network:
#: an interface at NetworkManager's hotspot address, and no default route
HOTSPOT = ("ip link set lo up && ip link add wlan0 type veth peer name phone && ip addr add 10.42.0.1/24 dev wlan0 && "
           "ip link set wlan0 up && ip link set phone up")
#: a network namespace and veth pairs to make one in (root, or a user namespace, and iproute2)
NAMESPACES = shutil.which("unshare") is not None and shutil.which("ip") is not None and subprocess.run(
    ["unshare", "-n", "sh", "-c", HOTSPOT], capture_output=True).returncode == 0


@pytest.mark.skipif(not NAMESPACES, reason="no network namespaces here (unshare -n and ip)")
def test_a_laptop_whose_only_network_is_its_hotspot_gives_the_students_its_address(tmp_path):
    # no default route, and the host name stands for 127.0.0.1: students were given no address at all
    code = "from ur10teach.serving.server import lan_addresses; print(lan_addresses())"
    done = subprocess.run(["unshare", "-n", "sh", "-c", f'{HOTSPOT} && exec "{sys.executable}" -c "{code}"'],
                          cwd=ROOT, capture_output=True, text=True, timeout=HANG_TIMEOUT)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["['10.42.0.1']"]
    # on no network at all, the teacher is told so, not to give the students "one of the addresses above"
    command = ["unshare", "-n", "sh", "-c", f'ip link set lo up && exec "{sys.executable}" -m ur10teach --port 0 --host 0.0.0.0']
    with serving(command, ROOT, dict(os.environ), timeout=HANG_TIMEOUT) as (_, output):
        text = "".join(output)
    assert "no network address that students could reach" in text and "one of the addresses above" not in text


def test_prints_the_real_port_when_the_asked_one_is_busy():
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        with running_app("--port", str(port)) as app:
            text = "".join(app.output)
    assert f"(port {port} was busy)" in text
    served = int(re.search(r"http://127\.0\.0\.1:(\d+)", app.url).group(1))
    assert served != port


def test_lan_address_and_join_code_in_shared_mode(tmp_path):
    with running_app("--host", "0.0.0.0", "--shared", "--arm", "scara", "--results", str(tmp_path / "results")) as app:
        text = "".join(app.output)
    assert "shared demo mode" in text
    assert f"their results are saved in {tmp_path / 'results'}" in text
    assert "Browsers open on the SCARA (RRP + roll); every arm stays in the picker." in text
    assert re.search(r"Join code for the presenter: [A-Z0-9]{3}-[A-Z0-9]{3}", text)
    for address in lan_addresses():
        assert f"http://{address}:" in text


def test_a_console_that_cannot_show_the_results_folders_name_still_starts_the_app(tmp_path):
    # printing "their results are saved in /…/résultats 结果" to a console in another code page (here ASCII; a
    # Windows console written to a file is in the system's code page) raised UnicodeEncodeError: the app stopped
    folder = tmp_path / "résultats 结果"
    with running_app("--shared", "--results", str(folder), env={"PYTHONIOENCODING": "ascii"}) as app:
        text = "".join(app.output)
    assert "their results are saved in " + str(folder).encode("ascii", "backslashreplace").decode() in text


def _children(pid: int) -> list[int]:
    """Every process the app started (Linux: /proc/PID/task/*/children)."""
    found = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        with contextlib.suppress(FileNotFoundError):
            found += [int(child) for child in (task / "children").read_text().split()]
    return found


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="reads /proc")
def test_the_app_starts_no_helpers_and_frees_its_port_when_killed():
    """A share request used to start two tunnel processes that outlived the app and kept its port."""
    async def visit(url: str, app) -> None:
        client = await ViserClient(url).connect()
        await client.send(messages.ShareUrlRequest())
        await until(lambda: any("dropped a ShareUrlRequest" in line for line in app.output), what="the request to be dropped")
        await client.close()

    with running_app("--shared") as app:
        asyncio.run(visit(app.url, app))
        assert _children(app.process.pid) == []
        port = int(re.search(r":(\d+)", app.url).group(1))
        app.process.send_signal(signal.SIGKILL)
        app.process.wait(timeout=HANG_TIMEOUT)
    with socket.socket() as again:  # a restarted app gets the same port
        again.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        again.bind(("127.0.0.1", port))


def test_a_launcher_without_the_main_guard_gets_one_server_and_its_slow_jobs_still_run(tmp_path):
    """The worker process ("spawn") runs the script that started the app again. A teacher's own launcher
    without ``if __name__ == "__main__":`` started a second server there, on the next port, and the first
    server's gravity drop, straight line or branch search waited on it for ever. Now the worker refuses to
    start a server and ends; the jobs run in the server, and no new worker is started for each."""
    import subprocess
    import sys

    launcher = tmp_path / "start_class.py"
    launcher.write_text(
        "from ur10teach.serving.server import TeachingServer\n"
        "from ur10teach.serving.workers import APART\n"
        "app = TeachingServer(port=0)\n"
        "print('a server started', flush=True)\n"
        "try:\n"
        "    print('jobs', APART.run(sum, [1, 2, 3]), APART.run(sum, [4, 5]), APART.processes_started, flush=True)\n"
        "finally:\n"
        "    app.stop()\n")
    done = subprocess.run([sys.executable, str(launcher)], capture_output=True, text=True, timeout=HANG_TIMEOUT,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.count("a server started") == 1 and "jobs 6 9 1" in done.stdout
    assert 'start the app under `if __name__ == "__main__":`' in done.stderr


def test_started_at_a_terminal_on_a_desktop_the_app_opens_its_page_in_the_browser(tmp_path):
    """A student who types the quick start's command expects the page to open, as Jupyter's does. Here the
    "browser" is the one ``$BROWSER`` names (Python's webbrowser tries it first): a script that writes down
    the address it is asked to open."""
    import pty

    opened = tmp_path / "opened.txt"
    browser = tmp_path / "browser"
    browser.write_text(f'#!/bin/sh\necho "$1" >> "{opened}"\n')
    browser.chmod(0o755)
    env = dict(os.environ, DISPLAY=":99", BROWSER=str(browser), PYTHONUNBUFFERED="1")
    terminal, its_end = pty.openpty()
    process = subprocess.Popen([sys.executable, "-m", "ur10teach", "--port", "0"], cwd=ROOT, env=env,
                               stdin=subprocess.DEVNULL, stdout=its_end, stderr=its_end)
    os.close(its_end)
    output = bytearray()

    def read() -> None:  # (a terminal whose output nobody reads fills up and stops the app)
        with contextlib.suppress(OSError):
            while chunk := os.read(terminal, 4096):
                output.extend(chunk)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        wait_for(lambda: opened.exists() and opened.read_text().strip() or None, what="the page opened")
        served = wait_for(lambda: re.search(rb"http://127\.0\.0\.1:\d+", bytes(output)), what="the address printed")
        assert opened.read_text().split() == [served.group().decode()]  # once, at the address it serves
    finally:
        process.terminate()
        process.wait(timeout=HANG_TIMEOUT)
        os.close(terminal)


@pytest.mark.parametrize("flags, at_a_terminal, opens", [((), True, True), (("--no-browser",), True, False),
                                                          ((), False, False)])
def test_the_page_is_opened_for_a_person_at_a_terminal_unless_told_not_to(monkeypatch, capsys, flags, at_a_terminal, opens):
    """Not for a script that reads the app's output (the tests, the benchmarks, a teacher's launcher), nor with
    ``--no-browser``."""
    import types

    import ur10teach.__main__ as entry

    asked = []
    monkeypatch.setattr(entry, "open_page", asked.append)
    monkeypatch.setattr(sys.stdout, "isatty", lambda: at_a_terminal)

    def interrupt(seconds: float) -> None:  # the app's wait for Ctrl+C: pressed at once
        raise KeyboardInterrupt

    monkeypatch.setattr(entry, "time", types.SimpleNamespace(sleep=interrupt))
    monkeypatch.setattr(signal, "signal", lambda *args: None)
    monkeypatch.setattr(entry.logs, "install", lambda: None)  # (the test process's logging stays pytest's)
    entry.main(["--port", "0", *flags])
    assert len(asked) == opens and all(url.startswith("http://127.0.0.1:") for url in asked)


def test_a_page_opens_only_where_a_browser_window_can(monkeypatch):
    """On Linux over SSH (no display) Python's webbrowser falls back to a text browser in the terminal the app
    prints to: nothing opens there."""
    import webbrowser

    import ur10teach.__main__ as entry

    asked = []
    monkeypatch.setattr(webbrowser, "open", asked.append)
    for name in ("DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    assert entry.open_page("http://127.0.0.1:8080") is None
    for platform, display in (("linux", ":0"), ("win32", None), ("darwin", None)):
        monkeypatch.setattr(sys, "platform", platform)
        if display:
            monkeypatch.setenv("DISPLAY", display)
        else:
            monkeypatch.delenv("DISPLAY", raising=False)
        entry.open_page(f"http://127.0.0.1:{len(asked)}").join(HANG_TIMEOUT)
    assert asked == ["http://127.0.0.1:0", "http://127.0.0.1:1", "http://127.0.0.1:2"]
