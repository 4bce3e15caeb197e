#!/usr/bin/env bash
# Install what the tests need, then run every test once, and the core's tests on its other backend.
#   - a Chromium for the browser tests (playwright drives it; it never downloads one): $UR10_TEACH_CHROMIUM,
#     a chromium on the PATH, or Debian's, installed with apt-get; and Debian's WebKitGTK WebDriver and Xvfb
#     for the one test in Safari's engine (Selenium drives it)
#   - a virtual environment ($UR10_TEST_VENV, default .venv-test) with the project and its
#     test extras; .ci/run points it at a new, empty folder every time
# Two runs share the two cores: the browser and install tests (mostly Chromium's and pip's work),
# beside everything else and then the core's tests on numpy. Each run's output is printed once both have ended.
# Extra arguments go to one pytest run on the default backend, e.g. scripts/test.sh -k ik
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${UR10_TEST_VENV:-.venv-test}"
STARTED=$SECONDS
stage() {  # stage NAME: a heading with the time since the start
    echo "== ($((SECONDS - STARTED)) s) $1"
}

# The browsers, from Debian where they are missing, in one apt-get run: the Chromium the browser tests drive
# ($UR10_TEACH_CHROMIUM, else a chromium on the PATH), and Safari's engine for its one test, WebKitGTK's WebDriver
# with a virtual screen (it has no headless mode; where there is no apt-get, that test is skipped)
DEBIAN_PACKAGES=()
if [ -z "${UR10_TEACH_CHROMIUM:-}" ] && ! command -v chromium >/dev/null 2>&1; then
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "no chromium here, and no apt-get to install Debian's: set UR10_TEACH_CHROMIUM to a Chromium" \
             "or Chrome binary for the browser tests (on macOS, for example," \
             "\"/Applications/Google Chrome.app/Contents/MacOS/Google Chrome\")" >&2
        exit 1
    fi
    DEBIAN_PACKAGES+=(chromium)
fi
if command -v apt-get >/dev/null 2>&1; then
    command -v WebKitWebDriver >/dev/null 2>&1 || DEBIAN_PACKAGES+=(webkit2gtk-driver)
    command -v Xvfb >/dev/null 2>&1 || DEBIAN_PACKAGES+=(xvfb)
fi
APT_PID=""
if [ ${#DEBIAN_PACKAGES[@]} -gt 0 ]; then
    debian_install() {
        $SUDO apt-get update -qq
        $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${DEBIAN_PACKAGES[@]}"
    }
    if [ "$(id -u)" = "0" ]; then  # (as CI runs) beside the venv's install: it takes about as long
        SUDO=""
        APT_LOG="$(mktemp)"
        stage "installing Debian's ${DEBIAN_PACKAGES[*]} for the browser tests, beside the venv"
        debian_install > "$APT_LOG" 2>&1 &
        APT_PID=$!
    else  # sudo may ask for a password
        SUDO="sudo"
        stage "installing Debian's ${DEBIAN_PACKAGES[*]} for the browser tests"
        debian_install
    fi
fi

stage "installing ur10-teach with its test dependencies into $VENV"
python3 -m venv "$VENV"
PYTHON="$VENV/bin/python"
# pip compiling every module it installs (all of sympy's, scipy's, matplotlib's ...) took 36 of a new
# venv's 83 s; Python compiles the few a test imports when it first imports them, and keeps them
# (where PYTHONDONTWRITEBYTECODE is set, as on the CI machine, every process would compile them again)
unset PYTHONDONTWRITEBYTECODE
"$PYTHON" -m pip install --quiet --disable-pip-version-check --no-compile -e ".[test]"
if [ -n "$APT_PID" ] && ! wait "$APT_PID"; then
    cat "$APT_LOG" >&2
    echo "apt-get could not install ${DEBIAN_PACKAGES[*]} (above)" >&2
    exit 1
fi
if [ -z "${UR10_TEACH_CHROMIUM:-}" ]; then
    UR10_TEACH_CHROMIUM="$(command -v chromium)"
    export UR10_TEACH_CHROMIUM
fi

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
browser_run() {
    "$PYTHON" -m pytest -m "browser or install" --durations=10
}
other_run() {
    "$PYTHON" -m pytest -m "not browser and not install" --durations=10
}

stage "two runs side by side, on the $BACKEND backend: the browser and install tests, and everything else"
# The numpy run follows whichever run passes first: which of the two is shorter changes from host to host
# and day to day (CI on 2026-12-02: browser and install tests 465 s beside 412 s; on 2026-12-06, 385 s beside
# 434 s), and the numpy run after the longer one made the whole 50 s longer.
# (in bash 3.2 too, macOS's own: no associative arrays, no wait -n; mkdir is atomic, so one lane takes it)
lane() {  # lane RUN: RUN's output into $LOGS/RUN.log; its exit code and when it ended (s) into $LOGS/RUN.end
    local code=0
    {
        "$1" && if mkdir "$LOGS/numpy_run" 2>/dev/null; then touch "$LOGS/numpy_run/$1"; numpy_run; fi
    } > "$LOGS/$1.log" 2>&1 || code=$?
    echo "$code $((SECONDS - STARTED))" > "$LOGS/$1.end"
}
lane browser_run &
lane other_run &
wait
FAILED=0
report() {  # report RUN WHAT: the run's result, at the time it ended, then its output
    local code ended what="$2"
    read -r code ended < "$LOGS/$1.end"
    if [ -e "$LOGS/numpy_run/$1" ]; then what="$what, then the core's tests on numpy"; fi
    echo "== ($ended s) $what: $([ "$code" -eq 0 ] && echo passed || echo "FAILED (exit $code)")"
    cat "$LOGS/$1.log"
    if [ "$code" -ne 0 ]; then FAILED=1; fi
}
BROWSER="browser and install tests"
OTHER="core, app and server tests"
read -r _ BROWSER_ENDED < "$LOGS/browser_run.end"
read -r _ OTHER_ENDED < "$LOGS/other_run.end"
if [ "$BROWSER_ENDED" -le "$OTHER_ENDED" ]; then
    report browser_run "$BROWSER"; report other_run "$OTHER"
else
    report other_run "$OTHER"; report browser_run "$BROWSER"
fi
rm -rf "$LOGS"
stage "done"
exit $FAILED
