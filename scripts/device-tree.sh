#!/usr/bin/env bash
# The GPU machine takes a copy of the working tree of at most 64 MiB (its carried paths
# included); scenes/ alone is 19 MB and docs/reports/ 42 MB. Before a device run, this leaves
# only the real scenes the run needs in the working tree and no committed report (git
# sparse-checkout: the rest stays committed, out of the folder); afterwards `--restore` puts
# every file back.
#
# usage: scripts/device-tree.sh SCENE...     (names of scenes/: sponza staircase dining-room
#                                            bathroom kitchen; none: no real scene)
#        scripts/device-tree.sh --restore
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = "--restore" ]; then
  git sparse-checkout disable
  exit 0
fi
for s in "$@"; do
  git cat-file -e "HEAD:scenes/$s.glb.xz" 2>/dev/null \
    || { echo "device-tree.sh: no scene $s in scenes/ (sponza staircase dining-room bathroom kitchen)" >&2; exit 1; }
done
{
  echo '/*'
  echo '!/docs/reports/'
  for f in $(git ls-files 'scenes/*.glb.xz'); do
    name=$(basename "$f" .glb.xz)
    case " $* " in
      *" $name "*) ;;
      *) echo "!/$f" ;;
    esac
  done
} | git sparse-checkout set --no-cone --stdin
echo "scenes in the working tree: $(cd scenes && ls ./*.glb.xz 2>/dev/null | tr '\n' ' ')(the rest committed; --restore puts them back)"
