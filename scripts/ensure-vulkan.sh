#!/usr/bin/env bash
# Checks what manylights needs on this machine and installs it where it can (Debian/Ubuntu, as
# root): a Rust toolchain (checked only), the Vulkan loader (libvulkan1) and a Vulkan driver
# (Mesa's lavapipe, mesa-vulkan-drivers, where there is no GPU driver). With --tests it also
# needs Debian's assimp-testmodels (real glTF files, good and malformed, used by the tests),
# Chromium (the HTML report is checked in a headless browser) and NumPy for the system Python
# (python3-numpy: the documented export script is run against the program's exports).
# Exits non-zero with the command to run when something is missing and cannot be installed.
set -euo pipefail

want_tests=0
[ "${1:-}" = "--tests" ] && want_tests=1

fail() { echo "ensure-vulkan: $*" >&2; exit 1; }

command -v cargo >/dev/null 2>&1 || fail "cargo not found: install Rust (https://rustup.rs), then run this again."

pkgs=()
ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' || pkgs+=(libvulkan1)
icds=$(ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json /usr/local/share/vulkan/icd.d/*.json 2>/dev/null || true)
[ -n "$icds" ] || [ -n "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ] || pkgs+=(mesa-vulkan-drivers)
if [ "$want_tests" = 1 ] && [ ! -d /usr/share/assimp/models/glTF2 ]; then pkgs+=(assimp-testmodels); fi
if [ "$want_tests" = 1 ] && ! command -v chromium >/dev/null 2>&1 && ! command -v chromium-browser >/dev/null 2>&1; then pkgs+=(chromium); fi
if [ "$want_tests" = 1 ] && ! /usr/bin/python3 -c 'import numpy' >/dev/null 2>&1 && ! python3 -c 'import numpy' >/dev/null 2>&1; then pkgs+=(python3-numpy); fi

if [ "${#pkgs[@]}" -gt 0 ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "ensure-vulkan: installing ${pkgs[*]}" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${pkgs[@]}" >/dev/null
  else
    fail "missing ${pkgs[*]}: run \`sudo apt-get install ${pkgs[*]}\` (or your distribution's Vulkan loader and Mesa Vulkan drivers), then run this again."
  fi
fi
echo "ensure-vulkan: ok (Vulkan drivers: $(ls /usr/share/vulkan/icd.d/ /etc/vulkan/icd.d/ 2>/dev/null | grep -c json || true) found)" >&2
