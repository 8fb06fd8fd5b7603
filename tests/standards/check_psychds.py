#!/usr/bin/python3
"""Checks a folder against the rules of the Psych-DS specification.

No Psych-DS validator is published on npm or in Debian, so the rules are
written out here from the specification's schema (psych-ds/psychds-validator,
src/setup/defaultSchema.json: rules.files, rules.errors, compiled_metadata),
each with the code the official validator reports:

  MISSING_DATASET_DESCRIPTION  dataset_description.json at the root
  JSON_INVALID                 it parses as UTF-8 JSON
  INVALID_JSONLD_FORMATTING    it is a JSON-LD object whose @context is schema.org
  MISSING_DATASET_TYPE         it has an @type ...
  INCORRECT_DATASET_TYPE       ... and the @type is "Dataset"
  JSON_KEY_REQUIRED            name, description, variableMeasured (after inheritance)
  MISSING_DATA_DIRECTORY       a data/ folder
  MISSING_DATAFILE             at least one valid data file under data/
  FILENAME_KEYWORD_FORMATTING_ERROR  data file names keyword-value pairs ending in _data.csv
  CSV_HEADER_MISSING, CSV_FORMATTING_ERROR, CSV_HEADER_LENGTH_MISMATCH  CSV rules
  ROWID_VALUES_NOT_UNIQUE      a row_id column holds unique values
  CSV_COLUMN_MISSING_FROM_METADATA  every column is in variableMeasured

Warnings (never fatal): FILENAME_UNOFFICIAL_KEYWORD_WARNING, OBJECT_TYPE_MISSING,
JSON_KEY_RECOMMENDED, MISSING_README_DOC.

Inheritance: data/**/file_metadata.json and a data file's .json sidecar
replace keys of dataset_description.json, nearest last.

Usage: check_psychds.py DATASET_DIR   (prints one line per error or warning, then a
summary; exit 0 without errors, 1 with errors, 2 for a bad argument)
"""
import csv
import json
import os
import re
import sys

OFFICIAL_KEYWORDS = {"study", "site", "subject", "session", "task", "condition", "trial",
                     "stimulus", "description"}
DATAFILE = re.compile(r"([a-z]+-[a-zA-Z0-9]+)(_[a-z]+-[a-zA-Z0-9]+)*_data\.csv")
REQUIRED = ("name", "description", "variableMeasured")
RECOMMENDED = ("author", "citation", "license", "funder", "url", "identifier", "privacyPolicy", "keywords")
SCHEMA_ORG = ("http://schema.org", "https://schema.org")


class Report:
    def __init__(self):
        self.errors = []
        self.warnings = []

    def error(self, code, where, what):
        self.errors.append(f"error {code}: {where}: {what}")

    def warning(self, code, where, what):
        self.warnings.append(f"warning {code}: {where}: {what}")


def load_json(path, rel, report):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        report.error("JSON_INVALID", rel, f"not valid UTF-8 JSON ({e})")
        return None


def is_schema_org(context):
    if isinstance(context, str):
        return context.rstrip("/").startswith(SCHEMA_ORG)
    if isinstance(context, dict):
        return is_schema_org(context.get("@vocab", ""))
    if isinstance(context, list):
        return any(is_schema_org(c) for c in context)
    return False


def check_description(doc, report):
    where = "dataset_description.json"
    if not isinstance(doc, dict):
        report.error("INVALID_JSONLD_FORMATTING", where, "expected a JSON object")
        return
    if not is_schema_org(doc.get("@context")):
        report.error("INVALID_JSONLD_FORMATTING", where,
                     f"@context {doc.get('@context')!r} is not schema.org (expected \"https://schema.org/\")")
    if "@type" not in doc and "type" not in doc:
        report.error("MISSING_DATASET_TYPE", where, "no @type (expected \"Dataset\")")
    elif doc.get("@type", doc.get("type")) not in ("Dataset", "schema:Dataset", "https://schema.org/Dataset",
                                                    "http://schema.org/Dataset"):
        report.error("INCORRECT_DATASET_TYPE", where, f"@type {doc.get('@type')!r}, expected \"Dataset\"")
    for key in RECOMMENDED:
        if key not in doc:
            report.warning("JSON_KEY_RECOMMENDED", where, f"no {key}")
    for i, v in enumerate(doc.get("variableMeasured") or []):
        if isinstance(v, dict) and "@type" not in v:
            report.warning("OBJECT_TYPE_MISSING", where, f"variableMeasured[{i}] has no @type")


def variable_names(metadata):
    names = set()
    for v in metadata.get("variableMeasured") or []:
        if isinstance(v, str):
            names.add(v)
        elif isinstance(v, dict) and isinstance(v.get("name"), str):
            names.add(v["name"])
    return names


def compiled_metadata(root, csv_path, base, report):
    """dataset_description.json, then file_metadata.json from data/ down, then the sidecar."""
    meta = dict(base)
    rel_dir = os.path.relpath(os.path.dirname(csv_path), root)
    parts = rel_dir.split(os.sep)
    for depth in range(1, len(parts) + 1):
        candidate = os.path.join(root, *parts[:depth], "file_metadata.json")
        if os.path.isfile(candidate):
            meta.update(load_json(candidate, os.path.relpath(candidate, root), report) or {})
    sidecar = csv_path[:-len(".csv")] + ".json"
    if os.path.isfile(sidecar):
        meta.update(load_json(sidecar, os.path.relpath(sidecar, root), report) or {})
    return meta


def check_filename(name, rel, report):
    if not DATAFILE.fullmatch(name):
        report.error("FILENAME_KEYWORD_FORMATTING_ERROR", rel,
                     "expected keyword-value pairs ending in _data.csv, e.g. study-x_subject-1_data.csv")
        return False
    for pair in name[:-len("_data.csv")].split("_"):
        keyword = pair.split("-", 1)[0]
        if keyword not in OFFICIAL_KEYWORDS:
            report.warning("FILENAME_UNOFFICIAL_KEYWORD_WARNING", rel, f"keyword {keyword!r} is not official")
    return True


def check_csv(path, rel, metadata, report):
    try:
        with open(path, encoding="utf-8", newline="") as f:
            rows = list(csv.reader(f, strict=True))
    except (UnicodeDecodeError, csv.Error) as e:
        report.error("CSV_FORMATTING_ERROR", rel, f"not parsable as UTF-8 CSV ({e})")
        return False
    if not rows or not any(cell.strip() for cell in rows[0]):
        report.error("CSV_HEADER_MISSING", rel, "no header row")
        return False
    header = rows[0]
    ok = True
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            report.error("CSV_HEADER_LENGTH_MISMATCH", f"{rel}:{line}",
                         f"{len(row)} fields, the header has {len(header)}")
            ok = False
    if "row_id" in header:
        j = header.index("row_id")
        values = [r[j] for r in rows[1:] if len(r) > j]
        if len(set(values)) != len(values):
            report.error("ROWID_VALUES_NOT_UNIQUE", rel, "row_id values repeat")
            ok = False
    missing = [c for c in header if c not in variable_names(metadata)]
    if missing:
        report.error("CSV_COLUMN_MISSING_FROM_METADATA", rel,
                     f"column(s) not in variableMeasured: {', '.join(missing)}")
        ok = False
    return ok


def check_dataset(root):
    report = Report()
    desc_path = os.path.join(root, "dataset_description.json")
    if not os.path.isfile(desc_path):
        report.error("MISSING_DATASET_DESCRIPTION", root, "no dataset_description.json at the root")
        return report
    base = load_json(desc_path, "dataset_description.json", report)
    if base is None:
        return report
    check_description(base, report)
    if not any(os.path.isfile(os.path.join(root, f"README{e}")) for e in (".md", ".txt")):
        report.warning("MISSING_README_DOC", root, "no README.md or README.txt")
    data_dir = os.path.join(root, "data")
    if not os.path.isdir(data_dir):
        report.error("MISSING_DATA_DIRECTORY", root, "no data/ folder")
        return report
    valid = 0
    for dirpath, _, files in sorted(os.walk(data_dir)):
        for name in sorted(files):
            if not name.endswith(".csv"):
                continue
            path = os.path.join(dirpath, name)
            rel = os.path.relpath(path, root)
            meta = compiled_metadata(root, path, base if isinstance(base, dict) else {}, report)
            for key in REQUIRED:
                if key not in meta:
                    report.error("JSON_KEY_REQUIRED", rel, f"the compiled metadata has no {key}")
            if check_filename(name, rel, report) and check_csv(path, rel, meta, report):
                valid += 1
    if valid == 0:
        report.error("MISSING_DATAFILE", "data/", "no valid CSV data file")
    return report


def main(argv):
    if len(argv) != 2 or not os.path.isdir(argv[1]):
        print("usage: check_psychds.py DATASET_DIR", file=sys.stderr)
        return 2
    report = check_dataset(argv[1])
    for line in report.errors + report.warnings:
        print(line)
    print(f"psych-ds: {len(report.errors)} errors, {len(report.warnings)} warnings")
    return 1 if report.errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
