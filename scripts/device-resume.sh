#!/usr/bin/env bash
# A long experiment run on the GPU machine over several device calls, each resuming the cells
# the calls before finished (a call is at most 10 minutes, and what comes back is at most 8
# files of 16 MiB).
#
# Here, before a call:  scripts/device-resume.sh prepare RUN_DIR
#   copies RUN_DIR/cells (a committed or fetched run; none: a fresh run) into .device/resume/
#   (carry .device; with scripts/device-tree.sh SCENE... for the scenes it needs).
# There, in the call:   bash scripts/device-resume.sh run EXPERIMENT SECONDS [STRATEGY BACKEND]
#   (.device/manylights, or .device/manylights.xz unpacked) runs EXPERIMENT with -v and --time-limit SECONDS into /tmp/resume over those cells, and
#   writes $OUT/run.tgz: results.csv, results.json, meta.json, run.log, every cell's JSON and
#   the renders, heatmaps and FLIP maps of the cells of STRATEGY with BACKEND (default zbin,
#   deferred; `all` keeps every cell's).
# Here, after it:       untar run.tgz into RUN_DIR, copy the experiment file in as
#   experiment.ron, `manylights report RUN_DIR`, commit.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  prepare)
    rm -rf .device/resume && mkdir -p .device/resume
    if [ -d "${2:?RUN_DIR}/cells" ]; then cp "$2"/cells/*.json .device/resume/; fi
    echo "device-resume: $(ls .device/resume | wc -l) finished cells in .device/resume"
    ;;
  run)
    exp=${2:?EXPERIMENT}; limit=${3:?SECONDS}; strategy=${4:-zbin}; backend=${5:-deferred}
    out=/tmp/resume
    [ -x .device/manylights ] || { unxz -k .device/manylights.xz && chmod +x .device/manylights; }
    mkdir -p "$out/cells"
    if compgen -G ".device/resume/*.json" > /dev/null; then cp .device/resume/*.json "$out/cells/"; fi
    ( time ./.device/manylights -v run "$exp" --out "$out" --time-limit "$limit" ) > "$out/run.log" 2>&1 || true
    keep=$(python3 - "$out" "$strategy" "$backend" <<'PY'
import csv, os, sys
out, strategy, backend = sys.argv[1:]
path = os.path.join(out, 'results.csv')
rows = list(csv.DictReader(open(path))) if os.path.exists(path) else []
for r in rows:
    if strategy == 'all' or (r['strategy'] == strategy and r['backend'] == backend):
        for kind in ('render', 'heat', 'flip'):
            f = f"images/{r['id']}_{kind}.png"
            if os.path.exists(os.path.join(out, f)):
                print(f)
PY
)
    # shellcheck disable=SC2086
    (cd "$out" && tar czf "$OUT/run.tgz" results.csv results.json meta.json run.log cells $keep)
    tail -n 4 "$out/run.log"
    ;;
  *)
    echo "usage: scripts/device-resume.sh prepare RUN_DIR | run EXPERIMENT SECONDS [STRATEGY BACKEND]" >&2
    exit 1
    ;;
esac
