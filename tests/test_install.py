"""A student's laptop: ``pip install .`` into a fresh venv with no C compiler, then the app starts, on the oldest
versions of its dependencies that ``pyproject.toml`` allows (a student may have them from another course).

Slow (it installs viser and friends into a new virtual environment): marked ``install``,
which ``scripts/test.sh`` runs.
"""

import asyncio
import os
import re
import shutil
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest

from ur10dev.app_process import serving
from ur10dev.viser_client import ViserClient
from ur10dev.waiting import HANG_TIMEOUT

ROOT = Path(__file__).resolve().parent.parent
pytestmark = pytest.mark.install
#: numpy 1.26 has no wheel for Python 3.13 and later; there, pip picks the newest releases
OLDEST_INSTALLABLE = sys.version_info < (3, 13)


def oldest_declared() -> dict[str, str]:
    """Each dependency of ``pyproject.toml`` that this Python installs, at the oldest version it allows."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:
        import tomli as tomllib
    oldest = {}
    for requirement in tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["dependencies"]:
        declared, _, marker = requirement.partition(";")
        named = re.fullmatch(r"\s*([\w.-]+)\s*[>=]=\s*([\w.]+)\s*", declared)
        assert named, f"{requirement!r}: each dependency names its oldest version, as name>=version or name==version"
        python_is = re.fullmatch(r"\s*python_version\s*<\s*'(\d+)\.(\d+)'\s*", marker)
        assert not marker or python_is, f"{requirement!r}: a marker other than python_version < 'X.Y'"
        if not python_is or sys.version_info < tuple(map(int, python_is.groups())):
            oldest[named[1].lower()] = named[2]
    return oldest


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, dict, str]:
    """A venv holding a normal (non-editable) install of this checkout, built with no compiler in reach, and
    what pip said."""
    folder = tmp_path_factory.mktemp("Zoë Müller")  # a home folder named as a student is: a space, letters beyond ASCII
    venv = folder / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    bin_dir = venv / ("Scripts" if os.name == "nt" else "bin")
    # only the venv on PATH: no gcc, cc or clang, as on a laptop without build tools
    env = dict(os.environ, PATH=str(bin_dir), CC="no-c-compiler-here", PIP_DISABLE_PIP_VERSION_CHECK="1")
    env.pop("UR10CORE_BACKEND", None)
    for compiler in ("gcc", "cc", "clang", "no-c-compiler-here"):
        assert shutil.which(compiler, path=env["PATH"]) is None
    # the checkout as a clone has it: pip builds in the source folder, and a kernel built there
    # before (an editable install, build/) would be packed into the wheel as if compiled now
    source = folder / "checkout"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", ".venv*", "build", "*.egg-info", "__pycache__", ".pytest_cache", ".ruff_cache", "*.so", "*.pyd"))
    oldest = folder / "oldest.txt"  # constraints: what is installed, not the build's own requirements
    oldest.write_text("".join(f"{name}=={at}\n" for name, at in oldest_declared().items()) if OLDEST_INSTALLABLE else "")
    done = subprocess.run(
        # --no-compile: what the tests below import is compiled as they import it (scripts/test.sh says why);
        # --verbose: the build's own warnings, which pip shows from release 24 on, are shown by this one too
        [str(bin_dir / "python"), "-m", "pip", "install", "--verbose", "--no-compile", "-c", str(oldest), str(source)],
        cwd=folder, env=env, capture_output=True, text=True, timeout=900,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return bin_dir, env, done.stdout + done.stderr


@pytest.mark.skipif(not OLDEST_INSTALLABLE, reason="numpy 1.26 has no wheel for this Python")
def test_the_oldest_versions_the_project_allows_are_the_ones_installed(installed, tmp_path):
    """What the tests below run on: had pip taken newer releases, a floor could be wrong and not seen (trimesh 4.0
    reads a PLY file of no faces as an empty list, and the app did not start with it)."""
    bin_dir, env, _ = installed
    oldest = oldest_declared()
    code = "import importlib.metadata as m, sys; print(*(m.version(n) for n in sys.argv[1:]))"
    done = subprocess.run([str(bin_dir / "python"), "-c", code, *oldest], cwd=tmp_path, env=env, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    assert {name: _release(at) for name, at in zip(oldest, done.stdout.split())} == \
        {name: _release(at) for name, at in oldest.items()}


def _release(version: str) -> tuple[int, ...]:
    """"1.26" → (1, 26, 0): a version as pip compares it (these floors have no letters)."""
    parts = tuple(int(part) for part in version.split("."))
    return parts + (0,) * (3 - len(parts))


def test_the_build_warns_of_nothing_a_newer_setuptools_would_refuse(installed):
    """Every install printed two warnings from setuptools, whose newest release the build fetches: the licence
    written as a table, which it stops building on 2027-02-18, and each mesh folder packed as data of a package
    it had not been told of ("Package would be ignored")."""
    *_, said = installed
    warnings = re.findall(r"\w*Warning: .*", said)
    assert not warnings, warnings


def test_the_core_installs_without_a_compiler_and_runs_on_numpy(installed, tmp_path):
    bin_dir, env, _ = installed
    code = (
        "import numpy as np, ur10core, pathlib; from ur10core import Arm;"
        "a = Arm.preset('course'); q = np.radians([45, 90, 0, -90, 0, 60]); s = a.ik(a.fk(q));"
        "k = Arm.preset('kr210'); kq = np.radians([10, 20, -30, 40, 50, 60]); ks = k.ik(k.fk(kq));"
        "print(ur10core.BACKEND, int(s.valid.sum()) + 100 * int(ks.valid.sum()), ur10core.__file__,"
        " sorted(p.name for p in pathlib.Path(ur10core.__file__).parent.glob('_kernels*')))"
    )
    done = subprocess.run([str(bin_dir / "python"), "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    backend, valid, location, kernels = done.stdout.split(maxsplit=3)
    assert backend == "numpy" and valid == "408"  # the UR10's 8 branches, the KR210's 4 (ur10core.solvers ships)
    assert str(ROOT) not in location  # the installed copy, not this checkout
    assert "_kernels.c" in kernels and ".so" not in kernels and ".pyd" not in kernels


def test_the_app_starts_from_another_directory(installed, tmp_path):
    bin_dir, env, _ = installed
    with serving([str(bin_dir / "ur10-teach"), "--port", "0"], tmp_path, env, timeout=HANG_TIMEOUT) as (app, output):
        url = re.search(r"http://127\.0\.0\.1:\d+", "".join(output)).group(0)
        with urllib.request.urlopen(url, timeout=HANG_TIMEOUT) as page:
            assert page.status == 200 and b"<html" in page.read().lower()

        async def a_student() -> None:  # a whole session built and drawn: the installed app serves a student
            client = await ViserClient(url).connect()
            assert client.gizmo_owner is not None and "θ1 base (°)" in client.gui
            await client.close()

        asyncio.run(a_student())
        assert app.poll() is None and "Traceback" not in "".join(output), "".join(output)
        assert "kinematics: numpy, no compiled kernel" in "".join(output)  # which backend, said where a teacher looks


def test_the_real_ur10_meshes_and_their_licence_ship(installed, tmp_path):
    bin_dir, env, _ = installed
    code = (
        "import ur10teach.meshes as m, pathlib; models = m.load_models('course');"
        "print(','.join(models.names), (m.MESH_DIR / 'real' / 'ur10' / 'LICENSE.md').is_file(), m.MESH_DIR, sep='|')"
    )
    done = subprocess.run([str(bin_dir / "python"), "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    names, licence, location = done.stdout.strip().split("|")
    assert names == "Real UR10,Schematic" and licence == "True"
    assert str(ROOT) not in location  # the installed copy's package data
