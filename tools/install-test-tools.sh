#!/bin/sh
# The test suite's system tools, installed only where missing: Chromium and ChromeDriver (the
# console's browser tests), Node.js and npm (the independent MCAP reader, @mcap/core), the venv
# module of Debian's own python3 (test_install.py installs the package with it) and systemd's
# systemd-analyze (test_deploy.py verifies the units).
#
# Each tool is asked for on its own condition and an installed one is never replaced: a machine
# whose Node.js came from another packager (nodesource) keeps it, because Debian's npm conflicts
# with that nodejs ("held broken packages"). Needs root and Debian's apt only when something is
# missing. APT_SIMULATE=1 runs apt-get in simulate mode (-s): nothing is installed (the tests).
set -u
missing=""
debian_python="${DEBIAN_PYTHON:-/usr/bin/python3}"
command -v chromium >/dev/null 2>&1 || missing="$missing chromium"
command -v chromedriver >/dev/null 2>&1 || missing="$missing chromium-driver"
if ! command -v node >/dev/null 2>&1; then
    missing="$missing nodejs"
    command -v npm >/dev/null 2>&1 || missing="$missing npm"
elif ! command -v npm >/dev/null 2>&1; then
    # a Node.js without npm: Debian's npm fits only Debian's nodejs
    if dpkg-query -W -f='${Version}' nodejs 2>/dev/null | grep -q nodesource; then
        echo "install-test-tools: node has no npm and is not Debian's: install npm with it" >&2
        exit 1
    fi
    missing="$missing npm"
fi
# Debian's python3 makes venvs only with python3-venv (ensurepip and its pip wheel)
"$debian_python" -c 'import ensurepip, venv' >/dev/null 2>&1 || missing="$missing python3-venv"
command -v systemd-analyze >/dev/null 2>&1 || missing="$missing systemd"
[ -z "$missing" ] && exit 0

simulate=""
[ "${APT_SIMULATE:-0}" = 1 ] && simulate="-s"
if [ -z "$simulate" ] && [ "$(id -u)" != 0 ]; then
    echo "install-test-tools: missing:$missing; run as root, or install them yourself" >&2
    exit 1
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "install-test-tools: missing:$missing, and this machine has no apt-get" >&2
    exit 1
fi
echo "install-test-tools: installing$missing" >&2
if [ -z "$simulate" ]; then
    apt-get update -qq || exit 1
fi
# shellcheck disable=SC2086
DEBIAN_FRONTEND=noninteractive apt-get install $simulate -y -qq $missing
