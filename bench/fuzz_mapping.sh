#!/usr/bin/env bash
# Fuzzes the HID mapping-file reader (and the report parser it configures)
# the same way bench/fuzz_protocol.sh fuzzes the protocol loader
# (bench/fuzz_run.sh), the corpus seeded with the mapping files under tests/,
# RUNS executions (default 1,000,000).
#   bash bench/fuzz_mapping.sh [RUNS] [extra libFuzzer flags…]
# Exit status is libFuzzer's: 0 when no crash, hang or sanitizer report.
set -euo pipefail
runs=${1:-1000000}
shift || true
exec bash "$(dirname "$0")/fuzz_run.sh" fuzz_mapping_file mapping_ tests/devices/fuzz_mapping.dict 4096 "$runs" \
  "tests/devices/data/*.toml" "$@"
