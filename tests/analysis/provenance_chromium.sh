#!/usr/bin/env bash
# The report's provenance table on a laptop screen: headless Chromium at
# 1366 × 768 loads the demo session's report, and a probe measures the
# table. It must fit the window without scrolling sideways, the page must
# not be wider than the window, and the protocol hash must show 12 hex
# digits with the full SHA-256 in the cell's title.
# Usage: provenance_chromium.sh SOURCE_DIR CURVLAB [SCREENSHOT.png]
set -uo pipefail
src=$1
curvlab=$2
shot=${3:-}
chromium_bin=$(command -v chromium || true)
[ -n "$chromium_bin" ] || { echo "FAIL: chromium is not installed; run: bash scripts/deps.sh all (Debian package chromium)"; exit 1; }
command -v Rscript >/dev/null || { echo "Rscript not found (apt-get install r-base-core): skipped"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$curvlab" run "$src/protocols/demo.toml" --participant P01 --db "$work/demo.sqlite" >"$work/run.log" 2>&1 ||
  { echo "FAIL: curvlab run of the demo"; cat "$work/run.log"; exit 1; }
Rscript "$src/analysis/report.R" --db "$work/demo.sqlite" --out "$work/report" --quiet >"$work/report.log" 2>&1 ||
  { echo "FAIL: report.R"; cat "$work/report.log"; exit 1; }

/usr/bin/python3 - "$work/report/report.html" "$work/probe.html" <<'PY'
import sys
page = open(sys.argv[1], encoding="utf-8").read()
probe = """<script>
window.addEventListener('load', () => {
  const table = document.querySelector('table.provenance');
  const box = table.parentElement;
  const header = [...table.querySelectorAll('thead th')].map(th => th.textContent);
  const cell = table.querySelector('tbody tr').children[header.indexOf('protocol_sha256')];
  const out = document.createElement('pre');
  out.id = 'probe';
  out.textContent = ['window', window.innerWidth, 'page', document.documentElement.scrollWidth,
                     'table', Math.ceil(table.getBoundingClientRect().width), 'box', box.clientWidth,
                     'hash', cell.textContent.length, 'title', (cell.title || '').length].join(' ');
  document.body.appendChild(out);
});
</script>"""
open(sys.argv[2], "w", encoding="utf-8").write(page.replace("</body>", probe + "\n</body>"))
PY
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --hide-scrollbars --user-data-dir="$work/profile"
       --window-size=1366,768)
timeout 120 "$chromium_bin" "${flags[@]}" --virtual-time-budget=5000 --dump-dom "file://$work/probe.html" \
  >"$work/dom.html" 2>"$work/chromium.log"
probe=$(grep -o '<pre id="probe">[^<]*</pre>' "$work/dom.html" | sed 's/<[^>]*>//g')
[ -n "$probe" ] || { echo "FAIL: Chromium produced no probe result"; tail -20 "$work/chromium.log"; exit 1; }
echo "chromium at 1366x768: $probe"
value() { sed -E "s/.*(^| )$1 ([0-9]+).*/\2/" <<<"$probe"; }
fail=0
[ "$(value window)" -eq 1366 ] || { echo "FAIL: the window is not 1366 px wide"; fail=1; }
[ "$(value page)" -le 1366 ] || { echo "FAIL: the page is $(value page) px wide, wider than the window"; fail=1; }
[ "$(value table)" -le "$(value box)" ] ||
  { echo "FAIL: the provenance table ($(value table) px) is wider than its box ($(value box) px)"; fail=1; }
[ "$(value hash)" -eq 12 ] || { echo "FAIL: the hash cell shows $(value hash) characters, expected 12"; fail=1; }
[ "$(value title)" -eq 64 ] || { echo "FAIL: the hash cell's title has $(value title) characters, expected 64"; fail=1; }
if [ -n "$shot" ]; then
  timeout 120 "$chromium_bin" "${flags[@]}" --screenshot="$shot" "file://$work/report/report.html" 2>/dev/null
  echo "screenshot: $shot"
fi
exit $fail
