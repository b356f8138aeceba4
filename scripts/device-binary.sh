#!/usr/bin/env bash
# The `manylights` binary of a commit, stripped and compressed for the GPU machine (which builds
# nothing: scripts/device-resume.sh unpacks .device/NAME.xz there). A/B runs take two: the
# commit before a change and the change.
#
# usage: scripts/device-binary.sh REV NAME    (REV: a commit, or `.` for the working tree)
#   builds REV in a worktree of its own under /tmp (its own target directory: a worktree built
#   into this tree's target/ would overwrite the workspace's crates there) and writes
#   .device/NAME.xz and .device/NAME.commit. With `.`, this tree's release build.
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:?REV (a commit, or . for the working tree)}; name=${2:?NAME}
if [ "$rev" = . ]; then
  cargo build --release --bin manylights
  bin=target/release/manylights
  commit="$(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo -dirty)"
else
  commit=$(git rev-parse --short "$rev")
  dir=/tmp/manylights-$commit
  [ -d "$dir" ] || git worktree add -f --detach "$dir" "$commit" >/dev/null
  CARGO_TARGET_DIR="$dir/target" cargo build --release --bin manylights --manifest-path "$dir/Cargo.toml"
  bin=$dir/target/release/manylights
fi
mkdir -p .device
# Line tables make the binary several times larger and xz minutes slower; the device needs none.
strip -o ".device/$name" "$bin"
xz -T0 -6 -f ".device/$name"
echo "$commit" > ".device/$name.commit"
echo "device-binary: .device/$name.xz ($(stat -c %s ".device/$name.xz") bytes) from $commit"
