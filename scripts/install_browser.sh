#!/bin/sh
# The browser of the web view's tests (test/unit/web/): Debian's chromium, driven by Playwright (PyPI) through
# executable_path. Idempotent: nothing to do when /usr/bin/chromium is there; as root it is installed with apt-get;
# otherwise one line says why not and the browser tests skip with that reason.
set -e
BROWSER=/usr/bin/chromium
if [ -x "$BROWSER" ]; then
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    echo "[setup] installing Debian's chromium for the browser tests (about a minute)"
    apt-get install -y --no-install-recommends chromium >/dev/null || {
        apt-get update >/dev/null && apt-get install -y --no-install-recommends chromium >/dev/null
    }
    [ -x "$BROWSER" ] && exit 0
fi
echo "install_browser.sh: $BROWSER is missing and cannot be installed here (needs root and apt-get: apt-get install chromium)"
