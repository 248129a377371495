#!/usr/bin/env python3
"""PointRT's layer rule (ARCHITECTURE.md), checked over the #include lines of the source tree.

    formats/  <-  runtime/core  <-  runtime/{cpu,cuda,host,backends}  <-  tools
                                                           (preprocess/*, preprocess/bench, runtime/player)

Arrows point down only:
  - a file includes only files of its own layer or of the layers below it;
  - runtime/core includes only itself and the layout headers of formats (prt/formats/*_layout.h):
    it is the PRT_HD code kernels compile, with no host library below it;
  - a tool includes of the runtime layer only its public headers (runtime/*/include/...), never
    runtime/*/src (the backends' internals);
  - tests/, scripts/ and data/ are not layers (tests may include anything).

An include is resolved like the build does: next to the including file, then in the project's
include folders (every `include/` folder and every preprocess/ and runtime/ folder that holds
headers); an include that names no file of the tree is a system or third-party header and is not
checked. Prints one line per violation (FILE:LINE: what) and exits 1 when there is any, 0 otherwise.

Usage: scripts/check-layers.py [--root DIR]   (default: the repository holding this script)
"""
import argparse
import os
import re
import sys

SOURCES = (".h", ".hpp", ".cuh", ".cpp", ".cc", ".cu")
LAYERS = {"formats": 0, "core": 1, "runtime": 2, "tools": 3}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def layer_of(rel):
    """The layer of a repository-relative path, or None when it is not in a layer."""
    parts = rel.split("/")
    if parts[0] == "formats":
        return "formats"
    if parts[0] == "runtime":
        if len(parts) > 1 and parts[1] == "core":
            return "core"
        if len(parts) > 1 and parts[1] in ("cpu", "cuda", "host", "backends"):
            return "runtime"
        if len(parts) > 1 and parts[1] == "player":
            return "tools"
        return None
    if parts[0] == "preprocess":
        return "tools"
    return None


def source_files(root):
    for top in ("formats", "runtime", "preprocess"):
        for d, _, files in os.walk(os.path.join(root, top)):
            for f in files:
                if f.endswith(SOURCES):
                    yield os.path.relpath(os.path.join(d, f), root).replace(os.sep, "/")


def include_folders(root, files):
    """Every folder the build may search: include/ trees and the folders that hold headers."""
    folders = set()
    for rel in files:
        d = os.path.dirname(rel)
        if rel.endswith((".h", ".hpp", ".cuh")):
            folders.add(d)
        parts = rel.split("/")
        if "include" in parts:
            folders.add("/".join(parts[:parts.index("include") + 1]))
    return sorted(folders)


def resolve(root, including, name, folders, known):
    local = os.path.normpath(os.path.join(os.path.dirname(including), name)).replace(os.sep, "/")
    if local in known:
        return local
    for f in folders:
        cand = os.path.normpath(os.path.join(f, name)).replace(os.sep, "/")
        if cand in known:
            return cand
    return None


def check(root):
    files = sorted(source_files(root))
    known = set(files)
    folders = include_folders(root, files)
    problems = []
    for rel in files:
        src = layer_of(rel)
        if src is None:
            continue
        with open(os.path.join(root, rel), errors="replace") as f:
            for n, line in enumerate(f, 1):
                m = INCLUDE.match(line)
                if not m:
                    continue
                target = resolve(root, rel, m.group(1), folders, known)
                if target is None:
                    continue  # a system or third-party header
                dst = layer_of(target)
                if dst is None:
                    continue
                where = "%s:%d: includes %s (%s)" % (rel, n, target, dst)
                if LAYERS[dst] > LAYERS[src]:
                    problems.append("%s: the %s layer may not include the %s layer above it" % (where, src, dst))
                elif src == "core" and dst == "formats" and not re.search(r"/prt/formats/\w*layout\.h$", target):
                    problems.append("%s: runtime/core includes only formats' layout headers" % where)
                elif src == "tools" and dst == "runtime" and "/include/" not in target:
                    problems.append("%s: tools use only the runtime's public headers (include/), not its src/"
                                    % where)
    return problems, len(files)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."),
                    help="the source tree to check (default: this repository)")
    args = ap.parse_args()
    problems, count = check(os.path.abspath(args.root))
    for p in problems:
        print(p)
    print("check-layers: %d files, %d violation%s" % (count, len(problems), "" if len(problems) == 1 else "s"),
          file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
