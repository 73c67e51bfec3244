#!/usr/bin/env python3
"""Man pages from the commands' own help, so that the pages, `--help` and the parser cannot drift apart.

usage: manpages.py THORAX OUTDIR [--date YYYY-MM-DD]

Writes OUTDIR/thorax.1 (from `thorax help`: the commands, each pointing at its page) and one
OUTDIR/thorax-CMD.1 per command (from `thorax CMD --help`); thorax-view.1 is `thorax view`'s page,
which is also the page of the program thorax-view that `thorax view` starts. Run at build time by
CMake (the `manpages` target); installed into share/man/man1. Exit 1 naming the command whose help
could not be read or parsed.

The help text's shape (src/cli/options.c prints it): a "usage:" block, paragraphs of prose, and
sections headed by an unindented lowercase line ending in ':' ("options:", "examples:", "surface
formats (by extension):"); an option is a line "  -o, --output DIR    text" whose text goes on at
a deeper indent; other indented lines are lists or examples, kept as they are.
"""
import os
import re
import subprocess
import sys
import tempfile

OPTION = re.compile(r"^  (-\S.*?)(?:\s{2,}(\S.*))?$")


def esc(text):
    """Escapes roff's specials in running text: backslash, and a leading dot or quote."""
    text = text.replace("\\", "\\e")
    if text.startswith((".", "'")):
        text = "\\&" + text
    return text


def code(text):
    """Text meant to be typed (options, synopsis, examples): hyphens are minus signs."""
    return esc(text).replace("-", "\\-")


def help_text(thorax, args):
    r = subprocess.run([thorax] + args, capture_output=True, text=True, timeout=60)
    out = r.stdout if r.stdout.strip() else r.stderr
    if r.returncode != 0 or not out.strip():
        sys.exit(f"manpages.py: '{' '.join([thorax] + args)}' failed (exit {r.returncode}): {r.stderr.strip()}")
    return out.rstrip("\n").split("\n")


def is_header(line, prev_blank):
    return (prev_blank and line[:1].islower() and line.endswith(":") and not line.startswith("usage:")
            and len(line) < 80)


def split_usage(lines):
    """The synopsis lines (without "usage: ") and the rest."""
    if not lines or not lines[0].startswith("usage:"):
        return [], lines
    syn, i = [], 0
    while i < len(lines) and lines[i].strip():
        line = lines[i].rstrip()
        # "usage: " is 7 characters: the continuation lines are indented by as many
        syn.append(line[7:] if i == 0 or line.startswith(" " * 7) else line.strip())
        i += 1
    return syn, lines[i:]


def body(lines):
    """roff for everything after the synopsis."""
    out = [".SH DESCRIPTION"]
    prev_blank, i = True, 0
    prose = False
    section = "DESCRIPTION"
    while i < len(lines):
        line = lines[i].rstrip()
        if not line:
            prev_blank, prose = True, False
            i += 1
            continue
        if is_header(line, prev_blank):
            # "volume mesh formats (a MESH is the only FILE; no --name/--role):" -> the heading in
            # capitals, the parenthesis as its first line, in its own case
            title, paren, rest = line[:-1].partition(" (")
            section = title.upper()
            out.append(".SH " + esc(section))
            if paren:
                out += [".PP", esc("(" + rest)]
            prev_blank, prose = False, False
            i += 1
            continue
        m = OPTION.match(line)
        if m:
            tag, text = m.group(1).rstrip(), [m.group(2)] if m.group(2) else []
            i += 1
            while i < len(lines) and lines[i].startswith("      ") and not OPTION.match(lines[i]):
                text.append(lines[i].strip())
                i += 1
            out.append(".TP")
            out.append("\\fB" + code(tag) + "\\fR")
            out.append(esc(" ".join(text)) if text else "")
            prev_blank, prose = False, False
            continue
        if line.startswith(" "):
            block = []
            while i < len(lines) and lines[i].startswith(" ") and not OPTION.match(lines[i]):
                block.append(lines[i].rstrip())
                i += 1
            out += [".RS 2", ".nf"] + [code(b[2:] if b.startswith("  ") else b.lstrip()) for b in block] + [".fi", ".RE"]
            prev_blank, prose = False, False
            continue
        if not prose:
            if "OPTIONS" in section and prev_blank:
                # prose after an option list (exit status, notes): a section of its own
                section = "NOTES"
                out.append(".SH NOTES")
            out.append(".PP")
            prose = True
        out.append(esc(line))
        prev_blank = False
        i += 1
    return out


def page(name, summary, version, date, synopsis, rest, see_also):
    out = [f'.TH {name.upper()} 1 "{date}" "thorax {version}" "thorax manual"',
           ".SH NAME", f"{code(name)} \\- {esc(summary)}"]
    if synopsis:
        out += [".SH SYNOPSIS", ".nf"] + [code(s) for s in synopsis] + [".fi"]
    out += body(rest)
    out += [".SH SEE ALSO", ",\n".join(f"\\fB{code(p)}\\fR(1)" for p in see_also)]
    out += [".SH LICENSE", "BSD 2-Clause (the LICENSE file, installed in share/doc/thorax)."]
    return "\n".join(out) + "\n"


def write(path, text):
    """Atomically: a temporary file in the same directory, renamed."""
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), prefix=".man.")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)


def main():
    args = sys.argv[1:]
    date = ""
    if "--date" in args:
        k = args.index("--date")
        date = args[k + 1]
        del args[k:k + 2]
    if len(args) != 2:
        print(__doc__)
        return 2
    thorax, outdir = args
    os.makedirs(outdir, exist_ok=True)
    version = help_text(thorax, ["--version"])[0].split()[-1]
    top = help_text(thorax, ["help"])
    commands = []
    on = False
    for line in top:
        if line.startswith("commands:"):
            on = True
            continue
        m = re.match(r"^  ([a-z]+)\s+(.*)$", line) if on else None
        if m and m.group(1) != "help":
            commands.append((m.group(1), m.group(2)))
        elif on and line and not line.startswith(" "):
            on = False
    if not commands:
        sys.exit(f"manpages.py: '{thorax} help' lists no commands")
    pages = ["thorax"] + [f"thorax-{c}" for c, _ in commands]
    written = []
    for cmd, summary in commands:
        syn, rest = split_usage(help_text(thorax, [cmd, "--help"]))
        if not syn:
            sys.exit(f"manpages.py: '{thorax} {cmd} --help' has no usage line")
        if cmd == "view":
            rest = rest + ["", "the program thorax-view:",
                           "  thorax view starts the program thorax-view (installed beside thorax), which",
                           "  links GTK 4; the batch commands do not load it."]
        name = f"thorax-{cmd}"
        write(os.path.join(outdir, name + ".1"),
              page(name, summary, version, date, syn, rest, ["thorax"]))
        written.append(name)
    # thorax(1): the overview and the list of commands, each pointing at its page
    syn, rest = split_usage(top)
    intro, listing = [], []
    for line in rest:
        if line.startswith("commands:"):
            break
        intro.append(line)
    listing = [".SH COMMANDS"]
    for cmd, summary in commands:
        listing += [".TP", f"\\fBthorax {code(cmd)}\\fR", esc(summary) + f" \\%(\\fBthorax\\-{code(cmd)}\\fR(1))"]
    listing += [".TP", "\\fBthorax help\\fR [\\fICOMMAND\\fR]", "the overview, or a command's help (as COMMAND \\-\\-help)"]
    first = []
    for line in intro:
        if not line.strip() and first:
            break
        if line.strip():
            first.append(line.strip())
    summary = re.sub(r"^thorax:\s*", "", " ".join(first)).rstrip(".") or "computational electrocardiology"
    text = page("thorax", summary, version, date, syn, intro, pages[1:])
    text = text.replace(".SH SEE ALSO", "\n".join(listing) + "\n.SH SEE ALSO", 1)
    write(os.path.join(outdir, "thorax.1"), text)
    print(f"manpages.py: {len(written) + 1} pages in {outdir}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
