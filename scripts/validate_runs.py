#!/usr/bin/env python3
"""validate_runs.py: checks runs against the run format's JSON Schema
(docs/schema/manifest.schema.json): each RUN's manifest.json against the schema, its run.json
against $defs/run_info and every frames/NNNNNN.json against $defs/frame.

Run:  scripts/validate_runs.py [--find] PATH...

A PATH is a run folder or a manifest.json; with --find, every run under each PATH (any folder
holding a manifest.json or a run.json) is checked. Prints one line per invalid file (the file,
the key path and the problem) and a count; exits 0 when every file is valid, 1 when one is not,
2 when there is nothing to check or the schema cannot be read. Needs python3-jsonschema.
"""
import json
import os
import sys

import jsonschema

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCHEMA = os.path.join(ROOT, "docs", "schema", "manifest.schema.json")


def validators():
    with open(SCHEMA) as f:
        schema = json.load(f)
    jsonschema.Draft202012Validator.check_schema(schema)
    cls = jsonschema.Draft202012Validator
    sub = lambda name: cls({"$ref": "#/$defs/" + name, "$defs": schema["$defs"]})
    return {"manifest": cls(schema), "run_info": sub("run_info"), "frame": sub("frame")}


def runs_under(path):
    for d, dirs, names in os.walk(path):
        dirs.sort()
        if "manifest.json" in names or "run.json" in names:
            yield d


def files_of(run):
    """(kind, path) of the JSON files of one run folder, or of one manifest file."""
    if os.path.isfile(run):
        return [("manifest", run)]
    out = []
    for name, kind in (("manifest.json", "manifest"), ("run.json", "run_info")):
        p = os.path.join(run, name)
        if os.path.isfile(p):
            out.append((kind, p))
    fd = os.path.join(run, "frames")
    if os.path.isdir(fd):
        out += [("frame", os.path.join(fd, n)) for n in sorted(os.listdir(fd))
                if n.endswith(".json") and n[:-5].isdigit()]
    return out


def main():
    args = sys.argv[1:]
    find = "--find" in args
    paths = [a for a in args if a != "--find"]
    if not paths:
        print(__doc__.strip().split("\n\n")[1], file=sys.stderr)
        return 2
    try:
        v = validators()
    except (OSError, ValueError, jsonschema.SchemaError) as e:
        print("validate_runs.py: %s: %s" % (SCHEMA, e), file=sys.stderr)
        return 2
    runs = [r for p in paths for r in (runs_under(p) if find else [p])]
    count = {"manifest": 0, "run_info": 0, "frame": 0}
    bad = 0
    for run in runs:
        for kind, path in files_of(run):
            count[kind] += 1
            try:
                with open(path) as f:
                    doc = json.load(f)
            except (OSError, ValueError) as e:
                print("%s: not JSON: %s" % (path, e))
                bad += 1
                continue
            errs = sorted(v[kind].iter_errors(doc), key=lambda e: list(e.absolute_path))
            if errs:
                bad += 1
                e = errs[0]
                where = "/".join(str(p) for p in e.absolute_path) or "(top)"
                print("%s: %s: %s%s" % (path, where, e.message[:200],
                                        " (+%d more)" % (len(errs) - 1) if len(errs) > 1 else ""))
    total = sum(count.values())
    print("%d manifests, %d run.json, %d frame records in %d runs: %d invalid"
          % (count["manifest"], count["run_info"], count["frame"], len(runs), bad))
    if total == 0:
        return 2
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
