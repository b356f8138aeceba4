#!/usr/bin/env bash
# A long experiment run on the GPU machine over several device calls, each resuming the cells
# the calls before finished (a call is at most 10 minutes, and what comes back is at most 8
# files of 16 MiB).
#
# Each experiment has its own resume folder and archive, named by its file (NAME for
# experiments/NAME.ron), so one call can run several experiments one after another.
#
# Here, before a call:  scripts/device-resume.sh prepare RUN_DIR [NAME]
#   copies RUN_DIR/cells (a committed or fetched run; none: a fresh run) into
#   .device/resume/NAME/ (NAME defaults to RUN_DIR's folder name; carry .device; with
#   scripts/device-tree.sh SCENE... for the scenes it needs).
# There, in the call:   [HARD_S=S] bash scripts/device-resume.sh run EXPERIMENT SECONDS [STRATEGY BACKEND]
#   (.device/manylights, or .device/manylights.xz unpacked) runs EXPERIMENT with -v and
#   --time-limit SECONDS into /tmp/resume/NAME over the cells of .device/resume/NAME, and
#   writes $OUT/NAME.tgz: results.csv, results.json, meta.json, run.log, every cell's JSON and
#   the renders, heatmaps and FLIP maps of the cells of STRATEGY with BACKEND (default zbin,
#   deferred; `all` keeps every cell's; KINDS="render" keeps only the renders). An archive over
#   15 MiB comes back in parts, NAME.tgz.part-aa, -ab, ... (a file that comes back is at most
#   16 MiB): cat them in order into NAME.tgz.
# Here, after it:       untar NAME.tgz into RUN_DIR, copy the experiment file in as
#   experiment.ron, `manylights report RUN_DIR`, commit.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  prepare)
    run_dir=${2:?RUN_DIR}; name=${3:-$(basename "$run_dir")}; dest=.device/resume/$name
    rm -rf "$dest" && mkdir -p "$dest"
    if [ -d "$run_dir/cells" ]; then cp "$run_dir"/cells/*.json "$dest/"; fi
    echo "device-resume: $(ls "$dest" | wc -l) finished cells in $dest"
    ;;
  run)
    exp=${2:?EXPERIMENT}; limit=${3:?SECONDS}; strategy=${4:-zbin}; backend=${5:-deferred}
    name=$(basename "$exp" .ron); out=/tmp/resume/$name; from=.device/resume/$name
    [ -x .device/manylights ] || { unxz -k .device/manylights.xz && chmod +x .device/manylights; }
    mkdir -p "$out/cells"
    if compgen -G "$from/*.json" > /dev/null; then cp "$from"/*.json "$out/cells/"; fi
    # HARD_S (seconds, optional): kill the run then, so that what it finished still comes back
    # before the call's own limit (a cell started before --time-limit runs to its end).
    hard=()
    if [ -n "${HARD_S:-}" ]; then hard=(timeout -k 5 "$HARD_S"); fi
    ( time "${hard[@]}" ./.device/manylights -v run "$exp" --out "$out" --time-limit "$limit" ) > "$out/run.log" 2>&1 || true
    keep=$(python3 - "$out" "$strategy" "$backend" "${KINDS:-render heat flip}" <<'PY'
import csv, os, sys
out, strategy, backend, kinds = sys.argv[1:]
path = os.path.join(out, 'results.csv')
rows = list(csv.DictReader(open(path))) if os.path.exists(path) else []
for r in rows:
    if strategy == 'all' or (r['strategy'] == strategy and r['backend'] == backend):
        for kind in kinds.split():
            f = f"images/{r['id']}_{kind}.png"
            if os.path.exists(os.path.join(out, f)):
                print(f)
PY
)
    # shellcheck disable=SC2086
    (cd "$out" && tar czf "$OUT/$name.tgz" --ignore-failed-read results.csv results.json meta.json run.log cells $keep)
    # A file that comes back is at most 16 MiB: a larger archive comes back in parts
    # (NAME.tgz.part-aa, -ab, ...; here: cat them in order into NAME.tgz).
    if [ "$(stat -c %s "$OUT/$name.tgz")" -gt $((15 * 1024 * 1024)) ]; then
      split -b 15M "$OUT/$name.tgz" "$OUT/$name.tgz.part-" && rm "$OUT/$name.tgz"
    fi
    tail -n 4 "$out/run.log"
    ;;
  *)
    echo "usage: scripts/device-resume.sh prepare RUN_DIR [NAME] | run EXPERIMENT SECONDS [STRATEGY BACKEND]" >&2
    exit 1
    ;;
esac
