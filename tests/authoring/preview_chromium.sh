#!/usr/bin/env bash
# `curvlab preview` in a real browser: headless Chromium loads the sheet,
# every image must load, and there is one condition panel per distinct
# condition of `curvlab design` (distinct factor levels and settings,
# practice trials apart, one per staircase). The
# sheet writes nothing outside its folder; a bad protocol gets the
# validator's messages, exit code 2 and no folder.
# Usage: preview_chromium.sh SOURCE_DIR CURVLAB PROTOCOL
set -uo pipefail
src=$1
curvlab=$2
protocol=$3
chromium_bin=$(command -v chromium || true)
if [ -z "$chromium_bin" ]; then
  echo "FAIL: chromium is not installed; run: bash scripts/deps.sh all (Debian package chromium)"
  exit 1
fi
py=/usr/bin/python3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/home" "$work/cwd"
fail=0

# 1. The sheet, run from an empty folder with an empty home.
(cd "$work/cwd" && HOME="$work/home" XDG_CACHE_HOME="$work/home/.cache" \
   "$curvlab" preview "$protocol" --out sheet --software) >"$work/preview.log" 2>&1
rc=$?
if [ $rc -ne 0 ]; then echo "FAIL: curvlab preview exited $rc"; cat "$work/preview.log"; exit 1; fi
grep -q 'rendering \[#*\] ' "$work/preview.log" || { echo "FAIL: no progress bar on stderr"; fail=1; }
# Nothing outside the output folder.
outside=$(cd "$work" && find cwd home -mindepth 1 -not -path 'cwd/sheet' -not -path 'cwd/sheet/*')
if [ -n "$outside" ]; then echo "FAIL: curvlab preview wrote outside its folder: $outside"; fail=1; fi
sheet="$work/cwd/sheet/index.html"
[ -s "$sheet" ] || { echo "FAIL: no $sheet"; exit 1; }

# 2. Distinct conditions according to curvlab design.
"$curvlab" design "$protocol" --participant 1 --json >"$work/design.json" || { echo "FAIL: curvlab design"; exit 1; }
expected=$("$py" - "$work/design.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
# Practice trials apart, and one per staircase.
print(len({json.dumps([t["levels"], t["settings"], t["practice"], t.get("staircase")], sort_keys=True)
           for t in d["trials"]}))
PY
)
echo "curvlab design: $expected distinct conditions"

# 3. Chromium loads a copy of the sheet with a probe that reports, after the
#    load event, how many images loaded and how many condition panels exist.
"$py" - "$sheet" "$work/probe.html" <<'PY'
import sys
page = open(sys.argv[1], encoding="utf-8").read()
probe = """<script>
window.addEventListener('load', () => {
  const imgs = [...document.images];
  const ok = imgs.filter(i => i.complete && i.naturalWidth > 0).length;
  const panels = document.querySelectorAll('section.condition').length;
  const out = document.createElement('pre');
  out.id = 'probe';
  out.textContent = ['images', imgs.length, 'loaded', ok, 'panels', panels].join(' ');
  document.body.appendChild(out);
});
</script>"""
assert "</body>" in page
open(sys.argv[2], "w", encoding="utf-8").write(page.replace("</body>", probe + "\n</body>"))
PY
timeout 120 "$chromium_bin" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync \
  --user-data-dir="$work/chromium-profile" --virtual-time-budget=10000 \
  --dump-dom "file://$work/probe.html" >"$work/dom.html" 2>"$work/chromium.log"
crc=$?
probe=$(grep -o '<pre id="probe">[^<]*</pre>' "$work/dom.html" | head -1)
if [ -z "$probe" ]; then
  echo "FAIL: Chromium (exit $crc) produced no probe result"; tail -20 "$work/chromium.log"; exit 1
fi
echo "chromium: $probe"
images=$(sed -E 's/.*images ([0-9]+).*/\1/' <<<"$probe")
loaded=$(sed -E 's/.*loaded ([0-9]+).*/\1/' <<<"$probe")
panels=$(sed -E 's/.*panels ([0-9]+).*/\1/' <<<"$probe")
[ "$images" -gt 0 ] || { echo "FAIL: the sheet has no images"; fail=1; }
[ "$loaded" -eq "$images" ] || { echo "FAIL: $((images - loaded)) of $images images did not load"; fail=1; }
[ "$panels" -eq "$expected" ] || { echo "FAIL: $panels condition panels, curvlab design has $expected conditions"; fail=1; }
[ "$images" -eq $((3 * panels)) ] || { echo "FAIL: expected left, right and anaglyph per panel"; fail=1; }

# The probe notices a broken image: the same page with one image's data cut.
sed '0,/data:image\/png;base64,/s//data:image\/png;base64,AAAA/' "$work/probe.html" >"$work/broken.html"
timeout 120 "$chromium_bin" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync \
  --user-data-dir="$work/chromium-profile" --virtual-time-budget=10000 \
  --dump-dom "file://$work/broken.html" 2>/dev/null | grep -o '<pre id="probe">[^<]*</pre>' >"$work/broken.txt"
grep -q "loaded $((images - 1)) " "$work/broken.txt" ||
  { echo "FAIL: the probe did not notice a broken image: $(cat "$work/broken.txt")"; fail=1; }

# 4. The sheet names the protocol's SHA-256 and the software version.
sha=$(sha256sum "$protocol" | cut -d' ' -f1)
grep -q "$sha" "$sheet" || { echo "FAIL: the sheet does not show the protocol's SHA-256 $sha"; fail=1; }
version=$("$curvlab" --version | cut -d' ' -f1)
grep -q "curvlab $version" "$sheet" || { echo "FAIL: the sheet does not show software version $version"; fail=1; }

# 5. A bad protocol: the validator's messages, exit 2, nothing written.
sed 's/^seed = 1$/seed = -5/; s/^\[timeline\]/[timeline]\nfixation_msec = 1/' "$src/protocols/demo.toml" >"$work/bad.toml"
"$curvlab" validate "$work/bad.toml" >"$work/validate.log" 2>&1
(cd "$work/cwd" && "$curvlab" preview "$work/bad.toml" --out bad_sheet) >"$work/bad_preview.log" 2>&1
brc=$?
[ $brc -eq 2 ] || { echo "FAIL: preview of a bad protocol exited $brc, expected 2"; fail=1; }
diff <(grep ': error: ' "$work/validate.log") <(grep ': error: ' "$work/bad_preview.log") >/dev/null ||
  { echo "FAIL: preview's messages differ from validate's"; diff "$work/validate.log" "$work/bad_preview.log"; fail=1; }
grep -q ': error: ' "$work/bad_preview.log" || { echo "FAIL: no error messages for the bad protocol"; fail=1; }
[ ! -e "$work/cwd/bad_sheet" ] || { echo "FAIL: preview of a bad protocol created its folder"; fail=1; }
exit $fail
