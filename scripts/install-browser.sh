#!/usr/bin/env bash
# Installs the headless browser the report's browser test drives (scripts/test-browser.sh):
# Debian's chromium at /usr/bin/chromium. A no-op when it is there already. Needs root (or
# sudo) and the distribution's package archive; Playwright's own browser download is not used.
set -euo pipefail
if [ -x /usr/bin/chromium ]; then
    echo "chromium: $(/usr/bin/chromium --version 2>/dev/null || echo present) at /usr/bin/chromium"
    exit 0
fi
if ! command -v apt-get >/dev/null; then
    echo "error: no apt-get here: install Chromium so that /usr/bin/chromium runs it" >&2
    exit 1
fi
sudo=""
if [ "$(id -u)" != 0 ]; then
    sudo="sudo"
fi
$sudo apt-get update
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends chromium chromium-driver
/usr/bin/chromium --version
