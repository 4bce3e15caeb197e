#!/usr/bin/env bash
# Install what the tests need, then run every test once, and the core's tests on its other backend.
#   - Debian's chromium for the browser tests (playwright drives it; it never downloads one)
#   - a virtual environment ($UR10_TEST_VENV, default .venv-test) with the project and its
#     test extras; .ci/run points it at a new, empty folder every time
# Two runs share the two cores: the browser and install tests (mostly Chromium's and pip's work),
# beside everything else and then the core's tests on numpy. Each run's output is printed when it ends.
# Extra arguments go to one pytest run on the default backend, e.g. scripts/test.sh -k ik
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${UR10_TEST_VENV:-.venv-test}"
STARTED=$SECONDS
stage() {  # stage NAME: a heading with the time since the start
    echo "== ($((SECONDS - STARTED)) s) $1"
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
# pip compiling every module it installs (all of sympy's, scipy's, matplotlib's ...) took 36 of a new
# venv's 83 s; Python compiles the few a test imports when it first imports them, and keeps them
# (where PYTHONDONTWRITEBYTECODE is set, as on the CI machine, every process would compile them again)
unset PYTHONDONTWRITEBYTECODE
"$PYTHON" -m pip install --quiet --disable-pip-version-check --no-compile -e ".[test]"

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

LOGS="$(mktemp -d)"
numpy_run() {
    if [ "$BACKEND" = "compiled" ]; then
        echo "== the core's tests again on the numpy backend (what a laptop without a C compiler runs)"
        UR10CORE_BACKEND=numpy "$PYTHON" -c 'import ur10core; print("backend:", ur10core.BACKEND)'
        # (the symbolic derivations, marked slow, are sympy's alone, and tests/test_backends.py calls
        # both backends side by side itself: once is enough)
        UR10CORE_BACKEND=numpy "$PYTHON" -m pytest -m "core and not slow" --ignore=tests/test_backends.py
    else
        echo "no C compiler here: the compiled backend is not built, its comparison tests are skipped"
    fi
}
# the numpy run follows the other run, now the shorter of the two (CI on 2026-12-02, after the symbolic
# derivations were cut from 160 s to 36 s: browser and install tests 465 s beside 412 + 62 s; 528 s in all)
browser_run() {
    "$PYTHON" -m pytest -m "browser or install" --durations=10
}
other_run() {
    "$PYTHON" -m pytest -m "not browser and not install" --durations=10 || return
    numpy_run
}

stage "two runs side by side, on the $BACKEND backend: the browser and install tests, and everything else"
declare -A NAME
browser_run > "$LOGS/browser.log" 2>&1 &
NAME[$!]="browser and install tests"
other_run > "$LOGS/other.log" 2>&1 &
NAME[$!]="core, app and server tests, then the core's tests on numpy"
FAILED=0
for _ in 1 2; do
    set +e
    wait -n -p DONE
    CODE=$?
    set -e
    LOG="$LOGS/other.log"
    if [ "${NAME[$DONE]}" = "browser and install tests" ]; then LOG="$LOGS/browser.log"; fi
    stage "${NAME[$DONE]}: $([ $CODE -eq 0 ] && echo passed || echo "FAILED (exit $CODE)")"
    cat "$LOG"
    if [ $CODE -ne 0 ]; then FAILED=1; fi
done
rm -rf "$LOGS"
stage "done"
exit $FAILED
