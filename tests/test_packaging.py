"""What a normal (non-editable) install ships: every package of the core and the app is listed."""

from __future__ import annotations

from pathlib import Path

from ur10core.challenges import tomllib  # (tomli before Python 3.11)

ROOT = Path(__file__).resolve().parent.parent


def test_every_python_package_is_declared_in_pyproject():
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    declared = set(setuptools["packages"])
    installed_as = {folder: name for name, folder in setuptools["package-dir"].items()}  # app/ → ur10teach
    found = set()
    for top in ("ur10core", "app"):
        for init in (ROOT / top).rglob("__init__.py"):
            parts = init.parent.relative_to(ROOT).parts
            found.add(".".join((installed_as.get(parts[0], parts[0]), *parts[1:])))
    assert found <= declared, f"not installed by pip install .: {sorted(found - declared)}"


def test_the_app_is_not_installed_under_a_bare_name():
    """Issue 29: the import name ``app`` collided with any other project's ``app`` in one environment."""
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert setuptools["package-dir"]["ur10teach"] == "app"
    assert not any(name == "app" or name.startswith("app.") for name in setuptools["packages"])


def test_nothing_imports_the_app_by_its_folder_name():
    """Importing ``app.x`` beside ``ur10teach.x`` would load the module twice, with two copies of its state."""
    import re

    bare = re.compile(r"^\s*(from app(\.| import)|import app\b)", re.M)
    sources = [path for top in ("app", "tests", "ur10dev", "benchmarks", "scripts") for path in (ROOT / top).rglob("*.py")]
    offenders = [str(path.relative_to(ROOT)) for path in sources if bare.search(path.read_text())]
    assert not offenders, offenders


def test_the_test_script_says_what_to_do_where_it_cannot_install_chromium(tmp_path):
    """On a machine without Debian's apt-get (macOS, say), ``scripts/test.sh`` ended on "apt-get: command not
    found": it now names the variable that points the browser tests at a Chromium or Chrome, before it builds
    anything."""
    import os
    import shutil
    import subprocess

    tools = tmp_path / "bin"  # a PATH with the shell's own tools only: no chromium, no apt-get
    tools.mkdir()
    for tool in ("bash", "dirname", "id"):
        (tools / tool).symlink_to(shutil.which(tool))
    env = {key: value for key, value in os.environ.items() if key != "UR10_TEACH_CHROMIUM"}
    env.update(PATH=str(tools), UR10_TEST_VENV=str(tmp_path / "venv"))
    result = subprocess.run([str(tools / "bash"), str(ROOT / "scripts" / "test.sh")], env=env, capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 1
    assert "set UR10_TEACH_CHROMIUM to a Chromium or Chrome binary" in result.stderr, result.stderr
    assert not (tmp_path / "venv").exists()
