#!/usr/bin/env bash
# System packages the tests use: Debian's chromium for the browser screenshot test.
# Installs them when missing and we are root with apt-get; otherwise prints why
# and lets the tests that need them skip with that reason.
set -u
if command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1; then
  exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
  echo "installing chromium (Debian package) for the browser tests..."
  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
    || echo "could not install chromium; browser tests will be skipped"
else
  echo "chromium not found and cannot install it here (need root and apt-get); browser tests will be skipped"
fi
exit 0
