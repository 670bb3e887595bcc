#!/usr/bin/env bash
# Installs the Debian 12 packages xylem needs to build, test and fuzz. Idempotent: when every
# package is present it prints nothing and touches nothing. Run as root (or with sudo).
set -euo pipefail

packages=(
  cmake ninja-build pkg-config gcc g++ make git
  clang libclang-rt-14-dev   # ASan/UBSan and libFuzzer runtimes for clang 14
  libcmocka-dev              # test framework
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "setup: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
