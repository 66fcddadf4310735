#!/usr/bin/env python3
"""Checks README.md and docs/*.md against the repository (ctest -L docs).

  check_docs.py ROOT [--crumble BIN] [--only FILE...]   check ROOT's documents
  check_docs.py --self-test [--crumble BIN]             the checker finds planted faults

What is checked, in every document:
  * links: every Markdown link [text](target) whose target is not a URL (scheme:) or an anchor
    alone (#...) names a file or folder that exists, relative to the document;
  * paths: every path named in the text or in code whose first component is a top-level entry
    of the repository (a folder or file tracked by git: `docs/`, `scenarios/`, `scripts/`,
    `README.md`, ...) exists. A path is left alone when a component is a placeholder: written
    in capitals (DIR, NAME, OUT), or holding `<`, `>`, `*`, `{`, `}`, `$`, `…` or `...`.
    Paths whose first component is not a top-level entry of the repository (`out/...`,
    `/tmp/...`, `build/...`, `vtk/...`, a run's files) are not repository paths and are not
    checked: the rule is the top-level entry, never a list of exceptions;
  * bare document names: a Markdown name in capitals without a folder (README.md, METHODS.md:
    the convention for a repository's own documents; lower-case names like comparison.md are
    files a command writes) names a document of the same folder or of the root, and must
    exist there;
  * outside references: no mention of documents a reader does not have (`/work/shared`, "the
    issue").
And in README.md, every `crumble ...` command (code blocks and inline code): its subcommand
exists and takes every option it is given (`crumble SUB --help` lists it). A command with
placeholders (capitals, `[`, `|`, `...`) is a synopsis, a subcommand without arguments is its
name, and a command loading a plugin (`--plugin`) needs a build the checker does not have:
they are checked no further. A concrete one is checked without running it: its scenario
exists and `crumble validate` accepts it with its --set values and each --vary / --param
value; `crumble list` and `crumble validate` are run as given. Comments (` #` to the end of
a code line) are not commands.
Exit 1 with one line per fault (FILE:LINE: what), 0 when there is none.
"""
import fnmatch
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
PATH = re.compile(r"(?<![\w/.~$-])((?:\.\./)*[A-Za-z0-9_][\w.+-]*(?:/[\w.+*<>{}$…-]*)+)")
BARE_MD = re.compile(r"(?<![\w/.-])([A-Z][A-Z0-9_-]*\.md)\b")
OUTSIDE = [re.compile(r"/work/shared"), re.compile(r"\bthe issue\b", re.I)]
PLACEHOLDER = re.compile(r"(^|[^A-Za-z])[A-Z][A-Z0-9_]*($|[^A-Za-z])|[<>*{}$…]|\.\.\.")
SYNOPSIS = re.compile(r"[\[\]|…]|\.\.\.|(^|[^A-Za-z0-9])[A-Z][A-Z0-9_]*($|[^A-Za-z0-9])")
CRUMBLE = re.compile(r"(?:^|[\s`])((?:\./|\$HOME/[\w-]+/)?(?:build[\w-]*/|bin/)?crumble)(\s.*)$")


def top_entries(root):
    """Top-level entries of the repository: tracked by git, else every visible entry."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files"], capture_output=True, text=True, check=True).stdout
        names = {line.split("/")[0] for line in out.splitlines() if line}
        if names:
            return names
    except (OSError, subprocess.CalledProcessError):
        pass
    # Not a git checkout (a `git archive` copy): every visible entry but those .gitignore
    # ignores at the top level (a run's out/, the build folders).
    ignored = []
    try:
        with open(os.path.join(root, ".gitignore")) as f:
            ignored = [p.strip().strip("/") for p in f if p.strip() and not p.startswith("#")]
    except OSError:
        pass
    return {n for n in os.listdir(root)
            if not n.startswith(".") and not any(fnmatch.fnmatch(n, p) for p in ignored)}


def documents(root):
    docs = [os.path.join(root, "README.md")] if os.path.exists(os.path.join(root, "README.md")) else []
    d = os.path.join(root, "docs")
    if os.path.isdir(d):
        docs += sorted(os.path.join(d, n) for n in os.listdir(d) if n.endswith(".md"))
    return docs


def strip_code_spans(line):
    return re.sub(r"`[^`]*`", lambda m: " " * len(m.group(0)), line)


def check_links(doc, n, line, faults):
    for m in LINK.finditer(strip_code_spans(line)):
        target = m.group(1)
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue
        path = target.split("#")[0]
        if not os.path.exists(os.path.join(os.path.dirname(doc), path)):
            faults.append(f"{doc}:{n}: broken link ({target})")


def check_paths(root, tops, doc, n, line, faults):
    for m in PATH.finditer(line):
        p = m.group(1).rstrip(".,;:!?'\"")
        first = p.split("/")[0]
        if first == ".." or first not in tops:
            continue
        if any(PLACEHOLDER.search(c) for c in p.split("/")):
            continue
        if not os.path.exists(os.path.join(root, p)):
            faults.append(f"{doc}:{n}: no such file or folder in the repository: {p}")
    for m in BARE_MD.finditer(line):
        name = m.group(1)
        if not any(os.path.exists(os.path.join(d, name)) for d in (os.path.dirname(doc), root)):
            faults.append(f"{doc}:{n}: {name} is not a document of the repository (not in {os.path.relpath(os.path.dirname(doc), root)}/ or the root)")
    for pat in OUTSIDE:
        for m in pat.finditer(line):
            faults.append(f"{doc}:{n}: refers to something a reader does not have: \"{m.group(0)}\"")


# ------------------------------------------------------------------ crumble commands


def commands(doc):
    """(line, command text) of every `crumble ...` command in code blocks and inline code."""
    out, fenced, pending, start = [], False, "", 0
    for n, line in enumerate(open(doc, encoding="utf-8").read().splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        code = fenced or line.startswith("    ") or line.startswith("\t")
        if code and pending:
            line = pending + " " + line.strip()
        elif code:
            start = n
        pending = ""
        if code and line.rstrip().endswith("\\"):
            pending = line.rstrip()[:-1]
            continue
        for c in [re.split(r"\s#", line)[0]] if code else re.findall(r"`([^`]+)`", line):
            m = CRUMBLE.search(" " + c)
            if m:
                out.append((start if code else n, re.split(r"\s(?:&&|;|#|\|\s)", m.group(2) + " ")[0].strip()))
    return out


def help_text(binary, words):
    r = subprocess.run([binary] + words + ["--help"], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def validate(binary, root, scenario, sets):
    args = [binary, "validate", os.path.join(root, scenario)]
    for s in sets:
        args += ["--set", s]
    r = subprocess.run(args, capture_output=True, text=True, cwd=root)
    return None if r.returncode == 0 else (r.stderr.strip().splitlines() or ["exit %d" % r.returncode])[-1]


def split_values(values):
    """a,b,c at the commas outside brackets ([1e6,2e6],[5e6] is two values)."""
    out, depth, cur = [], 0, ""
    for ch in values:
        depth += (ch == "[") - (ch == "]")
        if ch == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    return out + [cur]


def option_values(tokens, name):
    return [tokens[i + 1] for i, t in enumerate(tokens[:-1]) if t == name]


def study_runs(root, study, where, faults):
    """A study file (crumble sweep --study): its scenario (a file relative to the study's folder;
    an inline scenario is not checked), its `set` and one --set per swept value."""
    path = os.path.join(root, study)
    if not os.path.exists(path):
        faults.append(f"{where}: no study {study}")
        return None, [], []
    doc = json.load(open(path))
    if not isinstance(doc.get("scenario"), str):
        return None, [], []
    scenario = os.path.relpath(os.path.normpath(os.path.join(os.path.dirname(path), doc["scenario"])), root)
    runs = [[f"{p['path']}={json.dumps(v) if not isinstance(v, str) else v}"] for p in doc.get("params", [])
            for v in p.get("values", [])]
    return scenario, list(doc.get("set", [])), runs


def check_concrete(binary, root, sub, tokens, where, faults):
    if sub in ("list", "validate"):
        r = subprocess.run([binary] + tokens, capture_output=True, text=True, cwd=root)
        if r.returncode != 0:
            faults.append(f"{where}: `crumble {' '.join(tokens)}` fails: {(r.stderr.strip().splitlines() or [''])[-1]}")
        return
    if sub not in ("run", "compare", "sweep"):
        return
    study = option_values(tokens, "--study")
    scenario = next((t for t in tokens[1:] if t.endswith(".json") and not t.startswith("-") and t not in study), None)
    if study:
        scenario, sets, runs = study_runs(root, study[0], where, faults)
        if scenario is None:
            return
    if scenario is None:
        return
    if not os.path.exists(os.path.join(root, scenario)):
        faults.append(f"{where}: no scenario {scenario}")
        return
    if study:
        sets += option_values(tokens, "--set")
        runs = [sets] + [sets + r for r in runs]
        for r in runs:
            err = validate(binary, root, scenario, r)
            if err:
                faults.append(f"{where}: `crumble validate {scenario}` with {r or 'no --set'}: {err}")
        return
    sets = option_values(tokens, "--set")
    runs = [sets]
    for v in option_values(tokens, "--vary"):
        path, _, values = v.partition("=")
        runs += [sets + [f"{path}={x}"] for x in split_values(values)]
    for path, values in zip(option_values(tokens, "--param"), option_values(tokens, "--values")):
        runs += [sets + [f"{path}={x}"] for x in split_values(values)]
    for r in runs:
        err = validate(binary, root, scenario, r)
        if err:
            faults.append(f"{where}: `crumble validate {scenario}` with {r or 'no --set'}: {err}")


def check_command(binary, root, doc, n, cmd, faults):
    where = f"{doc}:{n}"
    try:
        tokens = shlex.split(cmd)
    except ValueError as e:
        faults.append(f"{where}: cannot split `crumble {cmd}`: {e}")
        return
    plugin = False
    while len(tokens) >= 2 and tokens[0] == "--plugin":
        tokens, plugin = tokens[2:], True
    if not tokens or tokens[0].startswith("-") or SYNOPSIS.search(tokens[0]):
        return  # crumble --help | --version, crumble --plugin lib.so …
    code, top = help_text(binary, [])
    sub = tokens[0]
    if not re.search(r"^\s+" + re.escape(sub) + r"\s", top, re.M):
        faults.append(f"{where}: `crumble {sub}`: no such subcommand")
        return
    code, text = help_text(binary, [sub])
    for t in tokens[1:]:
        opt = t.split("=")[0]
        if re.match(r"^--?[A-Za-z]", opt) and not re.search(r"(^|[\s,])" + re.escape(opt) + r"\b", text, re.M):
            faults.append(f"{where}: `crumble {sub}` has no option {opt}")
    if len(tokens) > 1 and not plugin and not any(SYNOPSIS.search(t) for t in tokens):
        check_concrete(binary, root, sub, tokens, where, faults)


# ------------------------------------------------------------------ main


def check(root, binary=None, only=None):
    root = os.path.abspath(root)
    tops = top_entries(root)
    faults = []
    for doc in documents(root):
        rel = os.path.relpath(doc, root)
        if only and rel not in only:
            continue
        fenced = False
        for n, line in enumerate(open(doc, encoding="utf-8").read().splitlines(), 1):
            if line.lstrip().startswith("```"):
                fenced = not fenced
            if not fenced:
                check_links(doc, n, line, faults)
            check_paths(root, tops, doc, n, line, faults)
        if binary and rel == "README.md":
            for n, cmd in commands(doc):
                check_command(binary, root, doc, n, cmd, faults)
    return [f.replace(root + "/", "") for f in faults]


def self_test(binary):
    """The checker must fail on each planted fault and pass on a clean tree."""
    ok = True
    with tempfile.TemporaryDirectory() as t:
        os.makedirs(os.path.join(t, "docs"))
        os.makedirs(os.path.join(t, "scenarios"))
        here = os.path.dirname(os.path.abspath(__file__))
        shutil.copy(os.path.join(here, "..", "..", "scenarios", "single_grain_pd.json"), os.path.join(t, "scenarios", "a.json"))
        open(os.path.join(t, "docs", "b.md"), "w").write("# b\n")
        clean = ("See [b](docs/b.md), `scenarios/a.json`, `out/run/series.csv`, `scenarios/NAME.json`, b.md.\n\n"
                 "    crumble run scenarios/a.json --out out/x --set breakage.type=stress   # a run\n"
                 "    crumble run SCENARIO --out DIR [--set path=value]...\n\n")
        open(os.path.join(t, "README.md"), "w").write(clean)
        if check(t):
            print("self-test: a clean tree was reported:", check(t))
            ok = False
        # A `git archive` copy after a run: out/ exists but .gitignore ignores it, so
        # `out/run/series.csv` is still not a repository path.
        os.makedirs(os.path.join(t, "out", "x"))
        open(os.path.join(t, ".gitignore"), "w").write("build*/\n/out/\n")
        if check(t):
            print("self-test: a run's out/ was taken for a repository folder:", check(t))
            ok = False
        planted = {
            "broken link": "See [gone](docs/gone.md).\n",
            "missing path": "Run `scenarios/missing.json`.\n",
            "bare document": "Background in METHODS.md.\n",
            "outside reference": "As the issue says.\n",
        }
        if binary:
            planted["unknown option"] = "    crumble run scenarios/a.json --out out/x --no-such-option\n"
            planted["invalid --set"] = "Run `crumble run scenarios/a.json --out x --set breakage.type=bogus`.\n"
            planted["invalid --vary value"] = "    crumble compare scenarios/a.json --out x --vary engine.type=bullet,bogus\n"
            planted["missing scenario"] = "    crumble run scenarios/gone.json --out x\n"
            planted["unknown subcommand"] = "Try `crumble frobnicate x`.\n"
        for what, text in planted.items():
            open(os.path.join(t, "README.md"), "w").write(clean + text)
            if not check(t, binary):
                print(f"self-test: the {what} was not found")
                ok = False
    print("self-test: ok" if ok else "self-test: FAILED")
    return 0 if ok else 1


def main(argv):
    binary = None
    if "--crumble" in argv:
        i = argv.index("--crumble")
        binary = os.path.abspath(argv[i + 1])
        del argv[i:i + 2]
    if argv and argv[0] == "--self-test":
        return self_test(binary)
    only = None
    if "--only" in argv:
        i = argv.index("--only")
        only, argv = set(argv[i + 1:]), argv[:i]
    if len(argv) != 1:
        print(__doc__)
        return 2
    faults = check(argv[0], binary, only)
    for f in faults:
        print(f)
    print(f"check_docs: {len(faults)} fault(s)" if faults else "check_docs: ok")
    return 1 if faults else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
