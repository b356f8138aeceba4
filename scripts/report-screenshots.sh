#!/usr/bin/env bash
# Screenshots of the committed reports as a reader sees them (headless Chromium, a 1000-pixel
# window): docs/reports/<name>/screenshot.png, the page from its title through its figures
# (the renders below them are left out to keep the files small). For review of the layout:
# the figures' legends, axes and labels and the results table at a normal window width.
# Usage: bash scripts/report-screenshots.sh [REPORT_DIR...]   (default: every docs/reports/*)
set -euo pipefail
cd "$(dirname "$0")/.."
chromium=$(command -v chromium || command -v chromium-browser || true)
[ -n "$chromium" ] || { echo "report-screenshots: needs Chromium: apt-get install chromium" >&2; exit 1; }
dirs=("$@")
[ "${#dirs[@]}" -gt 0 ] || dirs=(docs/reports/*/)
for d in "${dirs[@]}"; do
  d=${d%/}
  [ -f "$d/report.html" ] || continue
  # The height through the figures: a header and table of about 900 pixels, then each figure
  # at its height scaled to the 1000-pixel page, with its caption.
  h=900
  for f in "$d"/figures/*.svg; do
    [ -f "$f" ] || continue
    read -r w fh < <(sed -n 's/.*<svg width="\([0-9]*\)" height="\([0-9]*\)".*/\1 \2/p' "$f" | head -1)
    [ -n "${w:-}" ] || continue
    if [ "$w" -gt 968 ]; then fh=$((fh * 968 / w)); fi
    h=$((h + fh + 60))
  done
  # The results table's first 40 rows (a large sweep's table would make a page-long file).
  rows=$(($(wc -l < "$d/results.csv") - 1))
  [ "$rows" -le 40 ] || rows=40
  h=$((h + 20 * rows))
  "$chromium" --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1000,"$h" \
    --screenshot="$d/screenshot.png" "file://$PWD/$d/report.html" 2>/dev/null
  echo "$d/screenshot.png (1000 x $h)"
done
