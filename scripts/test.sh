#!/usr/bin/env bash
# Install what the tests need, then run every test once, and the core's tests on its other backend.
#   - Debian's chromium for the browser tests (playwright drives it; it never downloads one)
#   - a virtual environment ($UR10_TEST_VENV, default .venv-test) with the project and its
#     test extras; .ci/run points it at a new, empty folder every time
# Extra arguments go to one pytest run on the default backend, e.g. scripts/test.sh -k ik
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${UR10_TEST_VENV:-.venv-test}"
STARTED=$SECONDS
stage() {  # stage NAME: prints how long the previous stage took, then the new one's name
    echo "== ($((SECONDS - STARTED)) s so far) $1"
}

if ! command -v chromium >/dev/null 2>&1; then
    stage "installing Debian's chromium for the browser tests"
    SUDO=""
    if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
    $SUDO apt-get update -qq
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium
fi

stage "installing ur10-teach with its test dependencies into $VENV"
python3 -m venv "$VENV"
PYTHON="$VENV/bin/python"
"$PYTHON" -m pip install --quiet --disable-pip-version-check -e ".[test]"

# CPython 3.11's tracebacks parse source lines to place their ^^^ markers; a traceback
# formatted while the parser is busy in another frame trips a CPython bug
# (https://github.com/python/cpython/issues/106905). The fault tests make viser log
# plenty of them, so switch the markers off.
export PYTHONNODEBUGRANGES=1
if [ $# -gt 0 ]; then
    exec "$PYTHON" -m pytest "$@"
fi

BACKEND="$("$PYTHON" -c 'import ur10core; print(ur10core.BACKEND)')"
if [ "$BACKEND" != "compiled" ] && [ -n "${UR10_REQUIRE_COMPILED:-}" ]; then
    echo "the compiled kernel did not build (see pip's output with --verbose); CI requires it" >&2
    exit 1
fi
stage "every test once, on the $BACKEND backend: core, app, server, browser, install on a laptop without a compiler"
"$PYTHON" -m pytest -m "" --durations=15
if [ "$BACKEND" = "compiled" ]; then
    stage "the core's tests again on the numpy backend (what a laptop without a C compiler runs)"
    UR10CORE_BACKEND=numpy "$PYTHON" -c 'import ur10core; print("backend:", ur10core.BACKEND)'
    UR10CORE_BACKEND=numpy "$PYTHON" -m pytest -m core
else
    echo "no C compiler here: the compiled backend is not built, its comparison tests are skipped"
fi
stage "done"
