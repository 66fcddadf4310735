#!/usr/bin/env python3
"""Checks the folder layering of docs/architecture.md: every #include "folder/..." of a source
file points to its own folder or to a folder of a lower layer, and no two files include each
other through a chain (no file-level cycle). Exit 1 with the offending includes listed."""
import os
import re
import sys

# Layer of each top folder (longest prefix wins); a folder may include its own layer's folders
# only where listed in SIBLINGS.
LAYERS = {
    "base": 0, "geometry": 1, "geometry/cgal": 1, "core": 2,
    "backends": 3, "breakage": 3, "geometry/alpha_shape": 3, "geometry/level_set": 3,
    "output": 4, "scenarios": 5, "run": 6, "parallel": 6.5, "tools": 7, "apps": 8, "python": 8,
}
SIBLINGS = {("geometry/cgal", "geometry"), ("geometry", "geometry/cgal")}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+(?:/[a-z_]+)*)/[A-Za-z0-9_]+\.h"')


def folder_of(path):
    best = None
    for f in LAYERS:
        if path == f or path.startswith(f + "/"):
            if best is None or len(f) > len(best):
                best = f
    return best


def main(root):
    errors, graph = [], {}
    for top in LAYERS:
        d = os.path.join(root, top)
        if not os.path.isdir(d) or "/" in top:
            continue
        for dp, _, files in os.walk(d):
            for name in files:
                if not name.endswith((".cpp", ".h")):
                    continue
                rel = os.path.relpath(os.path.join(dp, name), root)
                src = folder_of(os.path.dirname(rel))
                with open(os.path.join(root, rel), errors="replace") as fh:
                    for ln, line in enumerate(fh, 1):
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        target = line.split('"')[1]
                        # A module is a header with its .cpp: X.cpp including X.h is no edge.
                        module, dep = os.path.splitext(rel)[0], os.path.splitext(target)[0]
                        if dep != module:
                            graph.setdefault(module, set()).add(dep)
                        dst = folder_of(m.group(1))
                        if dst is None or src is None or dst == src:
                            continue
                        if (src, dst) in SIBLINGS:
                            continue
                        if LAYERS[dst] >= LAYERS[src] and not (src.startswith("geometry/") and dst == "geometry"):
                            errors.append(f"{rel}:{ln}: {src} (layer {LAYERS[src]}) includes {target} "
                                          f"({dst}, layer {LAYERS[dst]})")
    errors += cycles(graph)
    for e in errors:
        print(e)
    print(f"{len(graph)} modules checked, {len(errors)} problems")
    return 1 if errors else 0


def cycles(graph):
    out, state = [], {}

    def visit(node, stack):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                out.append("file-level cycle: " + " -> ".join(stack[stack.index(nxt):] + [nxt]))
            elif nxt not in state:
                visit(nxt, stack)
        stack.pop()
        state[node] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n, [])
    return out


def self_test():
    """The checker itself: an upward include and a cycle in a made-up tree are both reported."""
    import tempfile
    with tempfile.TemporaryDirectory() as root:
        files = {"output/A.h": '#include "tools/B.h"\n', "tools/B.h": "", "core/C.h": '#include "core/D.h"\n',
                 "core/D.cpp": '#include "core/C.h"\n', "core/D.h": ""}
        for rel, text in files.items():
            os.makedirs(os.path.join(root, os.path.dirname(rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w") as fh:
                fh.write(text)
        found = main(root)
    print("self-test:", "ok" if found == 1 else "the checker missed a planted problem")
    return 0 if found == 1 else 1


if __name__ == "__main__":
    if sys.argv[1:] == ["--self-test"]:
        sys.exit(self_test())
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")))
