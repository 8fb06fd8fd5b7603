// A JSON Schema (draft-07) of the protocol format, for TOML editors and taplo.
// The settings sections, what a factor's `sets` may name and the values its
// levels may take come from the settings registry (settings.hpp) that the
// loader checks values against; the key and button names come from the
// loader itself. The structure of the other sections is declared here, and a
// test compares every section's keys and enumerations with the loader's own
// diagnostics, so the schema cannot drift from what `curvlab validate`
// accepts. Rules across fields (a square table in S3, start between min and
// max, a preset against a factor) stay in the loader: see docs/protocols.md,
// "What the schema checks and what only `curvlab validate` checks".
// Pure; thread-safe.
#pragma once

#include <string>

namespace curvlab::harness::protocol {

// The schema as indented JSON text ending in a newline: byte-for-byte what
// `curvlab schema` prints and protocols/schema.json holds.
std::string protocol_json_schema();

}  // namespace curvlab::harness::protocol
