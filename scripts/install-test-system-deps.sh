#!/usr/bin/env bash
# Install the system packages the certificate tests need (tests/test_certificate_render.py;
# without them those tests skip with the reason, so run this script first):
#   chromium        headless rendering of certificate.html (screenshot, --dump-dom)
#   poppler-utils   pdftoppm / pdftotext for the PDF checks
#   fonts-noto-cjk  CJK glyphs for `--lang zh`
#   postgresql      the server binaries (initdb, pg_ctl) the records tests start a throwaway
#                   cluster with (tests/records/conftest.py; the same tests run on SQLite);
#                   Chromium also serves the browser test of gonio serve (Playwright)
# Idempotent: packages already present are not reinstalled; `apt-get update` runs at most once.
# Without root or without apt-get it prints what to install and exits 0 (the tests then fail
# with a message pointing here).
set -u
PKGS="chromium poppler-utils fonts-noto-cjk postgresql"

missing=""
for p in $PKGS; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done
if [ -z "$missing" ]; then
    echo "install-test-system-deps: all present ($PKGS)"
    exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "install-test-system-deps: no apt-get on this system; install:$missing with your package manager" >&2
    exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
        SUDO="sudo -n"
    else
        echo "install-test-system-deps: not root (and no passwordless sudo); please install:$missing" >&2
        exit 0
    fi
fi
export DEBIAN_FRONTEND=noninteractive
echo "install-test-system-deps: installing$missing"
$SUDO apt-get update -qq || { echo "install-test-system-deps: apt-get update failed" >&2; exit 1; }
# shellcheck disable=SC2086
$SUDO apt-get install -y -qq --no-install-recommends $missing || {
    echo "install-test-system-deps: apt-get install failed for:$missing" >&2; exit 1; }
if command -v fc-cache >/dev/null 2>&1; then fc-cache -f >/dev/null 2>&1 || true; fi
echo "install-test-system-deps: done"
