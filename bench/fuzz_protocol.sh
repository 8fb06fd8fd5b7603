#!/usr/bin/env bash
# Fuzzes the protocol loader with libFuzzer + AddressSanitizer + UBSan
# (bench/fuzz_run.sh), the corpus seeded with protocols/ and the malformed
# corpus, RUNS executions (default 1,000,000).
#   bash bench/fuzz_protocol.sh [RUNS] [extra libFuzzer flags…]
# Exit status is libFuzzer's: 0 when no crash, hang or sanitizer report.
set -euo pipefail
runs=${1:-1000000}
shift || true
exec bash "$(dirname "$0")/fuzz_run.sh" fuzz_protocol_loader "" tests/protocol/fuzz_protocol.dict 8192 "$runs" \
  "protocols/*.toml tests/protocol/malformed/*.toml" "$@"
