#!/usr/bin/env bash
# Sourced by the scripts that run on the GPU machine: unpacks the Vulkan loader, and each
# xz-compressed executable of scripts/bench-bundle.sh in the folders given (FOLDER/NAME.xz ->
# FOLDER/NAME), where they are not unpacked yet.
ls .device/gl/*.deb > /dev/null 2>&1 \
  || echo "no Vulkan loader in .device/gl/: copy ../shared/device/gl/*.deb there (../shared/docs/DEVICE.md)" >&2
for f in .device/gl/*.deb; do [ -e "$f" ] && dpkg -x "$f" /; done
ldconfig
export XDG_RUNTIME_DIR=/tmp
for dir in "$@"; do
  for x in "$dir"/*.xz; do
    [ -e "$x" ] || continue
    [ -e "${x%.xz}" ] || { xz -dc "$x" > "${x%.xz}" && chmod +x "${x%.xz}"; }
  done
done
