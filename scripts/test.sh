#!/usr/bin/env bash
# Install what the tests need on a fresh machine, then run every test.
#   - Debian's chromium for the browser tests (playwright drives it; it never downloads one)
#   - the project with its test extras
# Extra arguments go to pytest, e.g. scripts/test.sh -k ik
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v chromium >/dev/null 2>&1; then
    echo "== installing Debian's chromium for the browser tests"
    SUDO=""
    if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
    $SUDO apt-get update -qq
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium
fi

echo "== installing ur10-teach with its test dependencies"
python3 -m pip install --quiet --disable-pip-version-check -e ".[test]"

echo "== running the tests"
# CPython 3.11's tracebacks parse source lines to place their ^^^ markers; a traceback
# formatted while the parser is busy in another frame trips a CPython bug
# (https://github.com/python/cpython/issues/106905). The fault tests make viser log
# plenty of them, so switch the markers off.
export PYTHONNODEBUGRANGES=1
exec python3 -m pytest "$@"
