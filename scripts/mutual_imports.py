#!/usr/bin/env python3
"""Lists the server crate's module pairs that import each other (`crate::a` in b and
`crate::b` in a), at the top level of `server/src` (a folder module counts as one module).

Usage: python3 scripts/mutual_imports.py [server/src]
"""
import os, re, sys, collections

root = sys.argv[1] if len(sys.argv) > 1 else "server/src"
mods = set()
for name in os.listdir(root):
    if name.endswith(".rs"):
        mods.add(name[:-3])
    elif os.path.isdir(os.path.join(root, name)):
        mods.add(name)
mods -= {"main", "lib"}

uses = collections.defaultdict(set)   # module -> modules it names through crate::
sub = re.compile(r"\bcrate::([a-z_][a-z0-9_]*)")
for dirpath, _, files in os.walk(root):
    for f in files:
        if not f.endswith(".rs"):
            continue
        path = os.path.join(dirpath, f)
        rel = os.path.relpath(path, root).split(os.sep)
        me = rel[0][:-3] if rel[0].endswith(".rs") else rel[0]
        if me not in mods:
            continue
        text = open(path, encoding="utf-8").read()
        # Tests do not count: only the module's own code.
        text = re.split(r"#\[cfg\(test\)\]", text)[0]
        # Nor comments (doc links name modules without importing them).
        text = re.sub(r"//[^\n]*", "", text)
        for m in sub.findall(text):
            if m in mods and m != me:
                uses[me].add(m)
pairs = sorted({tuple(sorted((a, b))) for a in list(uses) for b in uses[a] if a in uses.get(b, ())})
for a, b in pairs:
    print(f"{a} <-> {b}")
print(f"{len(pairs)} mutual pairs; {sum(1 for p in pairs if 'sessions' in p)} involve sessions")
