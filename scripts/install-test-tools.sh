#!/usr/bin/env bash
# Installs everything fleetsim's tests drive, so that a run of `python -m pytest -n 2` skips nothing:
# Debian's Tiled (the integration tests drive the real editor headless), Node.js (a planner in another
# language), Chromium (the reports and the viewer in a real headless browser), mosquitto (the VDA 5050
# tests against a real MQTT broker), a C compiler (the optional compiled build, built with mypyc); fleetsim with its test extras; the npm packages of the independent
# VDA 5050 master control and schema validators (tests/vda5050/node), exactly as locked.
# Used by the README's test command and by .ci/run. Needs root (or sudo) for apt-get on Debian/Ubuntu.
set -euo pipefail
cd "$(dirname "$0")/.."

export DEBIAN_FRONTEND=noninteractive
packages=()
command -v tiled >/dev/null 2>&1 || packages+=(tiled)
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)
command -v chromium >/dev/null 2>&1 || packages+=(chromium)
command -v gcc >/dev/null 2>&1 || packages+=(gcc)
{ command -v mosquitto >/dev/null 2>&1 || [ -x /usr/sbin/mosquitto ]; } || packages+=(mosquitto)
if [ ${#packages[@]} -gt 0 ]; then
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    echo "installing Debian packages: ${packages[*]}"
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq "${packages[@]}" >/dev/null
fi

python -m pip install -q --disable-pip-version-check -e '.[test]'
npm ci --prefix tests/vda5050/node --no-audit --no-fund --loglevel=error >/dev/null
