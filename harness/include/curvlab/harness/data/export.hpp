// Exporters: read a curvlab file and write analysis formats. They are kept
// apart from the logger and the algorithms (STYLE.md, "Algorithms separate
// from file formats"); see docs/data.md for the layouts.
#pragma once

#include "curvlab/harness/data/database.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::data {

struct ExportOptions {
  std::string out_dir;                    // created if missing
  std::optional<std::int64_t> session_id; // nullopt: every session
  std::string source = {};                // the data's origin as descriptions name it; empty: the file's
                                          // name (never a folder: a folder can name a person)
};

struct ExportSummary {
  std::vector<std::string> files;  // written, relative to out_dir
  std::size_t rows = 0;            // data rows written (trials or samples)
};

// Psych-DS and BIDS name files after participants and protocols by their
// letters and digits (P-01 → subject-P01, sub-P01): refused (bad_input,
// naming the pseudonyms or protocol names and the label) when two of the
// selected sessions' pseudonyms, or two protocol names, would get one label,
// also one that differs only in case (one file on a disk that ignores case),
// since one's files would overwrite the other's. Both exports check this
// before writing anything; a caller writing several formats checks first,
// so that none is written.
Expected<Done> check_export_labels(Database& db, const ExportOptions& options);

// One row per trial, wide: fixed columns, then cond_<name> and stim_<name>
// columns in order of first appearance. Missing values are NA. → trials.csv
Expected<ExportSummary> export_trials_csv(Database& db, const ExportOptions& options);
// Psych-DS dataset under out_dir/psychds/.
Expected<ExportSummary> export_psychds(Database& db, const ExportOptions& options);
// BIDS motion dataset under out_dir/bids/ (one tracking system per device).
Expected<ExportSummary> export_bids_motion(Database& db, const ExportOptions& options);

// The export formats, in the order `--format all` writes them: the one list
// `curvlab export` and `run --export` take them from. A new format is its
// exporter's file and one line in this list (export_common.cpp).
struct ExportFormat {
  std::string_view name;          // --format value; the summary's <name>_rows
  std::string_view run_folder;    // run --export DIR writes it under DIR/<run_folder>
  bool files_named_after_labels;  // names files after pseudonyms and protocols (check_export_labels)
  Expected<ExportSummary> (*write)(Database& db, const ExportOptions& options);
};
const std::vector<ExportFormat>& export_formats();

}  // namespace curvlab::harness::data
