#!/usr/bin/env python3
"""The bad-input table (docs/validation.md): malformed inputs, each run through the thorax
command that reads it, made from a valid base file by one small damage each.

Every format is a module here (tests/badinput/fmt_*.py) defining CASES, a list of
  Case(fmt, name, files, argv, out)
where files maps file names to bytes (written into a fresh temporary directory), argv is the
thorax command line (file names relative to that directory) and out is the output the command
would write ("" when it writes none). For every case the runner checks:
  1. exit status 1;
  2. the message (stderr) names the damaged file and a position: "FILE:LINE:" or
     "FILE: byte N" / "offset N" / "element"/"record" ... as the case's `where` regex says
     (default r"<file>:\\d+:" - the file and a line number);
  3. no output was written (out absent afterwards);
  4. an existing output (a valid one, written by the same command from the valid base
     first) is unchanged, byte for byte, when the bad input is run again over it with --force
     when the command takes it. Under the sanitizers (THORAX_QUICK, set by CMakeLists.txt) for
     every third case of each format only (the first, fourth, ...): the command fails in the
     same reader as in check 1, before any output is touched, so checking it for every damage
     repeats the same output path (half of this test's thorax runs); the plain build checks
     every case.
Usage: run.py THORAX [--table FILE.md] [--only FMT]
Exit 0 when every case passes; the table (format, damage, message) is written on request.
"""
import dataclasses
import glob
import hashlib
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor

sys.dont_write_bytecode = True  # nothing written into the source tree (tests/tree_clean.sh)


@dataclasses.dataclass
class Case:
    fmt: str                 # format name in the table, e.g. ".tri (OpenMEEG)"
    name: str                # the damage, e.g. "NUL byte in a coordinate"
    files: dict              # file name -> bytes
    argv: list               # thorax arguments (after "thorax"), file names relative to the dir
    out: str = ""            # the output path the command writes ("" = none)
    where: str = ""          # regex the message must match (default: first damaged file + ":LINE:")
    damaged: str = ""        # the file whose name the message must give (default: first of files)
    good: dict = None        # the valid base files, to write an existing output first (optional)
    force: bool = True       # the command takes --force (for the existing-output check)


def tree_digest(path):
    """A digest of a file or of a directory's names and contents (None if absent)."""
    if not os.path.lexists(path):
        return None
    h = hashlib.sha256()
    if os.path.isdir(path) and not os.path.islink(path):
        for root, dirs, files in sorted(os.walk(path)):
            dirs.sort()
            for f in sorted(files):
                p = os.path.join(root, f)
                h.update(os.path.relpath(p, path).encode() + b"\0")
                with open(p, "rb") as fh:
                    h.update(fh.read())
    else:
        with open(path, "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()


def run(thorax, d, argv):
    p = subprocess.run([thorax] + argv, cwd=d, capture_output=True, timeout=120)
    return p.returncode, p.stderr.decode("utf-8", "replace").strip()


_good_cache = {}
_good_lock = threading.Lock()


def good_output(thorax, c, g):
    """Fills the empty directory g with the valid base files and the output the command makes
    from them (made once per base and command line, then copied); returns an error or None."""
    h = hashlib.sha256("\0".join(c.argv).encode())
    for n in sorted(c.good):
        h.update(n.encode() + b"\0" + hashlib.sha256(c.good[n]).digest())
    key = h.hexdigest()
    with _good_lock:
        if key not in _good_cache:
            t = tempfile.mkdtemp(prefix="thorax-goodbase.")
            for n, b in c.good.items():
                os.makedirs(os.path.dirname(os.path.join(t, n)) or t, exist_ok=True)
                with open(os.path.join(t, n), "wb") as fh:
                    fh.write(b)
            rc0, msg0 = run(thorax, t, c.argv)
            _good_cache[key] = (t, None if rc0 == 0 else (msg0.splitlines()[0] if msg0 else f"exit {rc0}"))
        t, err = _good_cache[key]
    if err:
        return err
    shutil.copytree(t, g, symlinks=True, dirs_exist_ok=True)
    return None


def check_case(thorax, c, over_existing=True):
    """Returns (ok, message, problems); check 4 only when over_existing."""
    problems = []
    with tempfile.TemporaryDirectory(prefix="thorax-bad.") as d:
        for n, b in c.files.items():
            os.makedirs(os.path.dirname(os.path.join(d, n)) or d, exist_ok=True)
            with open(os.path.join(d, n), "wb") as fh:
                fh.write(b)
        rc, msg = run(thorax, d, c.argv)
        first = msg.splitlines()[0] if msg else ""
        if rc != 1:
            problems.append(f"exit {rc}, not 1")
        damaged = c.damaged or next(iter(c.files))
        where = c.where or (re.escape(damaged) + r":\d+:")
        if not re.search(where, msg):
            problems.append(f"message does not match /{where}/")
        if c.out and os.path.lexists(os.path.join(d, c.out)):
            problems.append(f"output {c.out} was written")
        # An existing output, made from the valid files, stays as it was.
        if over_existing and c.out and c.good is not None and not problems:
            with tempfile.TemporaryDirectory(prefix="thorax-good.") as g:
                err = good_output(thorax, c, g)
                if err:
                    problems.append(f"the valid base fails: {err}")
                else:
                    before = tree_digest(os.path.join(g, c.out))
                    for n, b in c.files.items():
                        with open(os.path.join(g, n), "wb") as fh:
                            fh.write(b)
                    argv = c.argv + (["--force"] if c.force else [])
                    rc1, _ = run(thorax, g, argv)
                    if rc1 != 1:
                        problems.append(f"over an existing output: exit {rc1}, not 1")
                    if tree_digest(os.path.join(g, c.out)) != before:
                        problems.append("the existing output was changed")
        return not problems, first, problems


def load_cases(only=None):
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, here)
    cases = []
    for path in sorted(glob.glob(os.path.join(here, "fmt_*.py"))):
        spec = importlib.util.spec_from_file_location(os.path.basename(path)[:-3], path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        for c in mod.CASES:
            if only is None or c.fmt == only or os.path.basename(path) == f"fmt_{only}.py":
                cases.append(c)
    return cases


def main():
    args = sys.argv[1:]
    if not args:
        print(__doc__)
        return 2
    thorax = os.path.abspath(args[0])
    table = None
    only = None
    if "--table" in args:
        table = args[args.index("--table") + 1]
    if "--only" in args:
        only = args[args.index("--only") + 1]
    cases = load_cases(only)
    failed = 0
    rows = []
    per_fmt = {}
    # two cases at a time: each is a few short thorax runs; the valid bases are made once
    quick = bool(os.environ.get("THORAX_QUICK"))
    nth = {}
    over = []
    for c in cases:
        nth[c.fmt] = nth.get(c.fmt, -1) + 1
        over.append(not quick or nth[c.fmt] % 3 == 0)
    with ThreadPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as ex:
        results = list(ex.map(lambda a: check_case(thorax, *a), zip(cases, over)))
    for t, _ in _good_cache.values():
        shutil.rmtree(t, ignore_errors=True)
    for c, (ok, first, problems) in zip(cases, results):
        per_fmt[c.fmt] = per_fmt.get(c.fmt, 0) + 1
        if not ok:
            failed += 1
            print(f"FAIL {c.fmt}: {c.name}: {'; '.join(problems)}\n     message: {first}")
        rows.append((c.fmt, c.name, first))
    for f, n in per_fmt.items():
        print(f"{f}: {n} cases" + ("" if n >= 20 else "  (fewer than 20)"))
    if quick:
        print(f"THORAX_QUICK: an existing output checked for {sum(over)} of the {len(cases)} cases")
    print(f"{len(cases)} bad inputs, {failed} failed")
    if table:
        with open(table, "w") as fh:
            fh.write("| format | damage | message (first line) |\n|---|---|---|\n")
            for f, n, m in rows:
                m = m.replace("|", "\\|")
                fh.write(f"| {f} | {n} | `{m}` |\n")
    short = [f for f, n in per_fmt.items() if n < 20]
    return 1 if failed or short or not cases else 0


if __name__ == "__main__":
    sys.exit(main())
