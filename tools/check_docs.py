#!/usr/bin/env python3
"""Checks the docs' citations of repository files (ctest: docs.check).

Citing docs: README.md, CHANGELOG.md, docs/*.md, and the README.md of bench/.
1. Every path a citing doc names that starts with a top-level folder of the
   repository (docs/, bench/, repro/, tools/, scripts/, jobs/, tests/, src/,
   include/, apps/, inputs/, cmake/) must exist. Paths with wildcards, braces
   or placeholders (NET.h5, test_<module>) are patterns, not citations, and
   are skipped; so are paths under build/ trees (tests/test_solver_mpi as run
   from a build directory is listed in docs/testing.md with its source).
2. Every file under docs/data/ must be cited by a citing doc: its path
   (docs/data/...) or its path relative to the folder it sits in, e.g.
   `perf/results-x.txt` or `results-x.txt` (docs/data/README.md, the index,
   is not a citing doc: being listed there alone does not count). A folder
   that holds one script's complete output counts as cited for all its files
   when a doc cites the folder (docs/data/ceres, docs/data/consensus/), and a
   doc's wildcard path (docs/data/consensus/fig67_*.csv) cites the files it
   matches; docs/data/ and docs/data/perf/, which hold single results, count
   for nothing as folders.
Exit status 1 with one line per problem; 0 when all is well.
  /usr/bin/python3 tools/check_docs.py [REPO_ROOT]
"""
import glob
import os
import re
import sys

root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
tops = "docs|bench|repro|tools|scripts|jobs|tests|src|include|apps|inputs|cmake"
path_re = re.compile(r"(?<![\w./-])((?:%s)/[\w.+/-]*[\w/])" % tops)


def citing_docs():
    out = [f for f in ("README.md", "CHANGELOG.md") if os.path.isfile(os.path.join(root, f))]
    out += sorted("docs/" + f for f in os.listdir(os.path.join(root, "docs")) if f.endswith(".md"))
    if os.path.isfile(os.path.join(root, "bench/README.md")):
        out.append("bench/README.md")
    return out


problems = []
texts = {}
for doc in citing_docs():
    with open(os.path.join(root, doc), encoding="utf-8") as fh:
        texts[doc] = fh.read()
    for n, line in enumerate(texts[doc].splitlines(), 1):
        for m in path_re.finditer(line):
            p = m.group(1)
            rest = line[m.end():m.end() + 1]
            if rest in "{*<" or p.endswith("_") or re.search(r"[A-Z]{2,}[\w]*\.", p.split("/")[-1]) or p.endswith("/X"):
                continue  # a pattern, not a file
            if not os.path.exists(os.path.join(root, p.rstrip("/"))):
                problems.append(f"{doc}:{n}: cites {p}, which does not exist")

alltext = "\n".join(texts.values())
covered = set()
for m in re.finditer(r"(?<![\w./-])(docs/data/[\w.+*/-]*[\w*/])", alltext):
    tok = m.group(1).rstrip("/")
    if tok in ("docs/data", "docs/data/perf"):
        continue
    if "*" in tok:
        covered.update(os.path.relpath(g, root) for g in glob.glob(os.path.join(root, tok)))
    elif os.path.isdir(os.path.join(root, tok)):
        for d, _, files in os.walk(os.path.join(root, tok)):
            covered.update(os.path.relpath(os.path.join(d, f), root) for f in files)
data = os.path.join(root, "docs", "data")
for d, _, files in os.walk(data):
    for f in files:
        full = os.path.relpath(os.path.join(d, f), root)
        if full == "docs/data/README.md":
            continue
        rel_data = os.path.relpath(os.path.join(d, f), data)
        if full in covered:
            continue
        if full not in alltext and rel_data not in alltext and not re.search(r"(?<![\w.-])%s(?![\w-])" % re.escape(f), alltext):
            problems.append(f"{full}: cited by no doc")

for p in problems:
    print(p)
print(f"check_docs: {len(texts)} docs, {len(problems)} problem(s)")
sys.exit(1 if problems else 0)
