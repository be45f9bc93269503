#!/usr/bin/env bash
# Installs Embree 3 (headers + libembree3.so) from Debian's packages: the only system dependency
# of the optional `embree` feature (`cargo build --release --features embree`), which adds
# Embree's rows to `parallax bench rays`. CI and the default build never need it.
# Run as root (or with sudo) on Debian/Ubuntu.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update
$SUDO apt-get install -y libembree-dev
ls /usr/include/embree3/rtcore.h >/dev/null
echo "Embree 3 installed: $(dpkg-query -W -f='${Version}' libembree3-3 2>/dev/null || echo '?')"
