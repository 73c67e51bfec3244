#!/usr/bin/env python3
"""Mutation testing: does the suite notice small deliberate bugs? (bench/mutate.sh runs this.)

bench/mutants.txt lists the mutants, one block each:
    ## NAME: what the bug is
    file: src/fem/assemble.c
    tests: REGEX            (the ctest -R regex of the tests that should kill it)
    - exact text (one or more lines, found exactly once in the file)
    + its replacement
A copy of the tree at HEAD (git worktree in a temporary directory) is built once; then each
mutant alone is applied, the tree rebuilt and its tests run; the mutant is killed when a test
fails (or the build fails: counted apart, as 'build', and not in the score). Prints per mutant
the tests that killed it, and the score killed / (killed + survived).
Usage: mutate.py [--dry-run] [--only NAME,...] [--baseline-passed]
"""
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def parse(path):
    muts, cur, mode = [], None, None
    for line in open(path).read().split("\n"):
        if line.startswith("## "):
            name, _, what = line[3:].partition(":")
            cur = {"name": name.strip(), "what": what.strip(), "file": "", "tests": "", "old": [], "new": []}
            muts.append(cur)
        elif cur is None or line.startswith("#") and not line.startswith("##"):
            continue
        elif line.startswith("file:"):
            cur["file"] = line[5:].strip()
        elif line.startswith("tests:"):
            cur["tests"] = line[6:].strip()
        elif line.startswith("- "):
            cur["old"].append(line[2:])
        elif line.startswith("+ "):
            cur["new"].append(line[2:])
        elif line == "+":
            cur["new"].append("")
    for m in muts:
        m["old"] = "\n".join(m["old"])
        m["new"] = "\n".join(m["new"])
    return muts


def apply(tree, m):
    p = os.path.join(tree, m["file"])
    src = open(p).read()
    n = src.count(m["old"])
    if n != 1:
        return f"text found {n} times in {m['file']}"
    open(p, "w").write(src.replace(m["old"], m["new"]))
    return None


def targets(build, regex):
    """The build targets the tests matching regex need (test_X, fuzz_replay_X; thorax for e2e)."""
    r = run(["ctest", "-N", "-R", regex], build)
    names = re.findall(r"Test +#\d+: (\S+)", r.stdout)
    t = {"thorax_cli"}
    for n in names:
        if n.startswith("test_") or n.startswith("fuzz_replay_"):
            t.add(n)
    return sorted(t)


def test_names():
    """The ctest names CMakeLists.txt makes from the tree (tests/test_*.c, tests/e2e_*.sh, fuzz replays)."""
    t = os.path.join(ROOT, "tests")
    names = ["python_binding", "phantom_models", "tree_stamp", "tree_clean"]
    for f in sorted(os.listdir(t)):
        if re.fullmatch(r"test_\w+\.c", f) or re.fullmatch(r"e2e_\w+\.sh", f):
            names.append(f.rsplit(".", 1)[0])
    for f in sorted(os.listdir(os.path.join(t, "fuzz"))):
        if re.fullmatch(r"fuzz_\w+\.c", f):
            names.append("fuzz_replay_" + f[5:-2])
    return names


def run(cmd, cwd, timeout=None):
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)


def main():
    args = sys.argv[1:]
    dry = "--dry-run" in args
    only = None
    if "--only" in args:
        only = set(args[args.index("--only") + 1].split(","))
    jobs = os.environ.get("JOBS", "2")
    muts = parse(os.path.join(HERE, "mutants.txt"))
    if only:
        muts = [m for m in muts if m["name"] in only]
    bad = 0
    names = test_names()
    for m in muts:
        src = open(os.path.join(ROOT, m["file"])).read() if os.path.exists(os.path.join(ROOT, m["file"])) else ""
        n = src.count(m["old"]) if m["old"] else 0
        if n != 1 or not m["tests"]:
            print(f"mutant {m['name']}: does not apply: text found {n} times in {m['file']}" + ("" if m["tests"] else ", no tests"))
            bad += 1
        elif not any(re.search(m["tests"], t) for t in names):
            # ctest -R with a regex that matches nothing runs nothing and passes: the mutant would
            # "survive" untested (a space-separated list is one such regex)
            print(f"mutant {m['name']}: tests regex {m['tests']!r} matches no test")
            bad += 1
    modules = sorted({m["file"].split("/")[1] for m in muts if m["file"].startswith("src/")})
    print(f"{len(muts)} mutants over {len(modules)} modules ({', '.join(modules)})")
    if dry or bad:
        return 1 if bad else 0
    tmp = tempfile.mkdtemp(prefix="thorax-mutate.")
    tree, build = os.path.join(tmp, "tree"), os.path.join(tmp, "build")
    head = run(["git", "rev-parse", "--short", "HEAD"], ROOT).stdout.strip()
    run(["git", "worktree", "add", "--detach", tree, "HEAD"], ROOT)
    # the end-to-end tests find the shared data next to the source tree, as in the real checkout
    shared = os.path.join(os.path.dirname(ROOT), "shared")
    if os.path.isdir(shared):
        os.symlink(shared, os.path.join(tmp, "shared"))
    print(f"tree: HEAD {head} in {tree}")
    try:
        r = run(["cmake", "-S", tree, "-B", build, "-DCMAKE_BUILD_TYPE=RelWithDebInfo"], tree)
        r = run(["cmake", "--build", build, "-j", jobs], tree)
        if r.returncode:
            print("the unmutated tree does not build:\n" + r.stdout[-2000:] + r.stderr[-2000:])
            return 1
        # The unmutated tree must pass every test a mutant uses, or a kill means nothing
        # (--baseline-passed: the caller has just seen the suite pass at this HEAD, e.g. make check).
        regex = "|".join(sorted({m["tests"] for m in muts}))
        r = None
        if "--baseline-passed" in args:
            print("baseline: taken as passed (--baseline-passed)")
        else:
            r = run(["ctest", "-R", regex, "-j", jobs, "--timeout", "600"], build)
        if r is not None and r.returncode:
            print("the unmutated tree fails its tests:\n" + r.stdout[-3000:])
            return 1
        killed = survived = broke = 0
        print(f"{'mutant':<28} {'result':<9} {'s':>5}  killed by / what")
        for m in muts:
            t0 = time.time()
            err = apply(tree, m)
            if err:
                print(f"{m['name']:<28} {'error':<9} {0:5.0f}  {err}")
                continue
            r = run(["cmake", "--build", build, "-j", jobs, "--target"] + targets(build, m["tests"]), tree)
            if r.returncode:
                broke += 1
                res, who = "build", "does not compile"
            else:
                r = run(["ctest", "-R", m["tests"], "-j", jobs, "--timeout", "600"], build)
                failed = re.findall(r"\d+ - (\S+) \(", r.stdout)
                if r.returncode and failed:
                    killed += 1
                    res, who = "killed", " ".join(failed)
                elif r.returncode:
                    killed += 1
                    res, who = "killed", "ctest failed: " + r.stdout.strip().splitlines()[-1]
                else:
                    survived += 1
                    res, who = "SURVIVED", m["what"]
            run(["git", "checkout", "--", m["file"]], tree)
            print(f"{m['name']:<28} {res:<9} {time.time() - t0:5.0f}  {who}", flush=True)
        run(["cmake", "--build", build, "-j", jobs], tree)
        total = killed + survived
        print(f"score: {killed}/{total} killed = {100.0 * killed / max(total, 1):.1f}%"
              f" ({broke} did not compile, not counted); HEAD {head}")
        return 0 if total and killed >= 0.9 * total else 1
    finally:
        run(["git", "worktree", "remove", "--force", tree], ROOT)
        run(["rm", "-rf", tmp], ROOT)


if __name__ == "__main__":
    sys.exit(main())
