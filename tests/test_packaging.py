"""What a normal (non-editable) install ships: every package of the core and the app is listed."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_every_python_package_is_declared_in_pyproject():
    declared = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(init.parent.relative_to(ROOT).parts)
             for top in ("ur10core", "app") for init in (ROOT / top).rglob("__init__.py")}
    assert found <= declared, f"not installed by pip install .: {sorted(found - declared)}"
