#!/usr/bin/env bash
# Opens a `parallax report` page in headless Chromium and prints its self-check (images that did
# not load, plot SVGs without marks, console errors), the same check as the browser test of
# `crates/cli/tests/experiment.rs`; writes a screenshot beside the page.
#   tools/check_report.sh out/experiments/widmer_table2_warp/index.html
# Exit status: 0 when the page reports data-status="ok", 1 otherwise, 2 without a browser.
set -euo pipefail
page="${1:?usage: tools/check_report.sh PAGE.html}"
chrome="$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)"
if [ -z "$chrome" ]; then
  echo "no chromium on PATH (Debian: apt-get install chromium)" >&2
  exit 2
fi
url="file://$(realpath "$page")"
flags=(--headless --no-sandbox --disable-gpu --no-first-run --disable-extensions --virtual-time-budget=20000)
check="$("$chrome" "${flags[@]}" --dump-dom "$url" 2>/dev/null | grep -o '<[^>]*id="selfcheck"[^>]*>' || true)"
"$chrome" "${flags[@]}" --hide-scrollbars --window-size=1280,2400 \
  --screenshot="${page%.html}.png" "$url" >/dev/null 2>&1 || true
echo "${check:-no self-check found}"
echo "screenshot: ${page%.html}.png"
case "$check" in *'data-status="ok"'*) exit 0 ;; *) exit 1 ;; esac
