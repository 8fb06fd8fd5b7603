#!/usr/bin/env bash
# `curvlab new`: a copy of an example with its name, version and seed set,
# which validates (with curvlab and with taplo through its #:schema
# directive), and which is never overwritten.
# Usage: new_protocol.sh SOURCE_DIR CURVLAB
set -uo pipefail
src=$1
curvlab=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
cd "$work"
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }

"$curvlab" new pilot-study --from proposed_study --dir protocols --seed 4242 >new.log 2>&1
check '[ $? -eq 0 ]' "curvlab new exits 0"
f=protocols/pilot-study.toml
check '[ -s $f ]' "it writes protocols/pilot-study.toml"
check 'grep -qx "name = \"pilot-study\"" $f' "the name is set"
check 'grep -qx "version = \"0.1.0\"" $f' "the version is 0.1.0"
check 'grep -qx "seed = 4242" $f' "the seed is set"
check '! grep -q "20210731" $f' "the example's seed is gone"
# Everything else, comments included, is the example's.
check 'diff <(grep -v "^name = \|^version = \|^seed = \|^#:schema" $src/protocols/proposed_study.toml) <(grep -v "^name = \|^version = \|^seed = \|^#:schema" $f) >/dev/null' "the rest of the example is copied unchanged"
check '"$curvlab" validate $f >validate.log 2>&1' "the new protocol validates"
schema_line=$(head -1 $f)
check '[ "${schema_line#\#:schema }" != "$schema_line" ] && [ -f "protocols/${schema_line#\#:schema }" ]' "its #:schema directive points at protocols/schema.json ($schema_line)"
taplo="$src/tools/node_modules/.bin/taplo"
if [ -x "$taplo" ]; then
  check '"$taplo" lint --no-auto-config --colors never $f >taplo.log 2>&1' "taplo validates it through the directive"
else
  echo "FAIL: taplo is not installed at $taplo; run: bash scripts/deps.sh all"; fail=1
fi

# A fresh seed when none is given; two protocols get different seeds.
"$curvlab" new second --dir protocols >/dev/null 2>&1 && "$curvlab" new third --dir protocols >/dev/null 2>&1
check '[ "$(grep ^seed protocols/second.toml)" != "$(grep ^seed protocols/third.toml)" ]' "fresh seeds differ"
check 'grep -qx "name = \"second\"" protocols/second.toml' "the default example (demo) is copied"

# Never overwrite.
before=$(sha256sum $f)
"$curvlab" new pilot-study --from demo --dir protocols >again.log 2>&1
check '[ $? -eq 2 ]' "a second curvlab new of the same name exits 2"
check 'grep -q "already exists" again.log' "and says the file exists"
check '[ "$(sha256sum $f)" = "$before" ]' "and leaves the file unchanged"

# Bad names and unknown examples are usage errors.
"$curvlab" new "Bad Name" --dir protocols >bad.log 2>&1
check '[ $? -eq 2 ]' "a name that is not an identifier exits 2"
"$curvlab" new fine --from nonexistent --dir protocols >bad2.log 2>&1
check '[ $? -eq 2 ] && grep -q "proposed_study" bad2.log' "an unknown example exits 2 and lists the examples"
check '[ ! -e protocols/fine.toml ]' "and writes nothing"
# A --from file that is no protocol is refused before anything is written:
# one past the loader's 1 MiB limit (here a valid protocol padded with
# comments, which validate would refuse), and one that does not load.
{ cat "$src/protocols/demo.toml"; yes "# padding padding padding padding padding padding padding" | head -c 2000000; } >big.toml
"$curvlab" new big --from big.toml --dir protocols >big.log 2>&1
check '[ $? -eq 2 ] && grep -q "larger than 1 MiB" big.log' "a --from file over 1 MiB exits 2 and says why"
check '[ ! -e protocols/big.toml ]' "and writes nothing"
printf '[protocol]\nname = "x"\nversion = "1"\nbogus = 1\n[randomization]\nseed = 1\n' >broken.toml
"$curvlab" new broken --from broken.toml --dir protocols >broken.log 2>&1
check '[ $? -eq 2 ] && grep -q "broken.toml" broken.log' "a --from file that does not load exits 2 naming it"
check '[ ! -e protocols/broken.toml ]' "and writes nothing"
if [ $fail -ne 0 ]; then cat new.log again.log bad.log bad2.log validate.log big.log broken.log 2>/dev/null; fi
exit $fail
