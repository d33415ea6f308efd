#!/usr/bin/env python3
"""Counts that show whether the crates' paths and public surfaces tell the truth (ARCHITECTURE.md,
"Code map"): root aliases of other crates' modules, `crate::` paths that lead into another crate,
`pub` items no other crate names, notes and errors kept as plain text, errors that print their cause
and also return it, command-line flag names below the command line, and test lines against code
lines per crate. It reads the sources as text, so a
count is a place to look, not a verdict.

    python3 scripts/house-counts.py
"""
import os
import re
import sys

CRATES = ["shared", "recording", "estimator", "outputs", "app", "device", "host"]
# Other code that names the crates: the end-to-end tests, the fuzz targets, the Python package, the
# firmware (which names `shared`).
OUTSIDE = ["tests", "fuzz", "python", "firmware"]
BELOW_EDGE = ["shared", "recording", "estimator", "outputs", "app", "device"]


def rust_files(root):
    for dp, dn, fn in os.walk(root):
        dn[:] = [d for d in dn if d not in ("target", ".git", ".venv")]
        for f in fn:
            if f.endswith(".rs"):
                yield os.path.join(dp, f)


def is_test_file(path):
    name = os.path.basename(path)
    return (re.search(r"(^|_)tests?\.rs$", name) is not None or "/tests/" in path
            or "/benches/" in path or "/examples/" in path)


def split_code(path):
    """(code lines, test lines) of a file: a file's test module starts at `#[cfg(test)]` followed
    by an inline `mod NAME {`."""
    lines = open(path, errors="replace").read().split("\n")
    if is_test_file(path):
        return [], lines
    for i, line in enumerate(lines):
        if line.startswith("#[cfg(test)]") and i + 1 < len(lines) and re.match(
                r"\s*(pub\s+)?mod\s+\w+\s*\{", lines[i + 1]):
            return lines[:i], lines[i:]
    return lines, []


def root_aliases(crate):
    """Names a crate's lib.rs brings in from other workspace crates with a root `use`/`pub use`."""
    text = open(os.path.join(crate, "src", "lib.rs")).read()
    aliases = {}
    for m in re.finditer(r"^(?:pub )?use (?:::)?(\w+)::\{([^}]*)\};|^(?:pub )?use (?:::)?(\w+)::(\w+);|^pub use ::(\w+);",
                         text, re.M):
        if m.group(1):
            other, names = m.group(1), [n.strip() for n in m.group(2).split(",") if n.strip()]
        elif m.group(3):
            other, names = m.group(3), [m.group(4)]
        else:
            other, names = m.group(5), [m.group(5)]
        if other in CRATES and other != crate:
            for n in names:
                if re.fullmatch(r"[a-z_]+", n):
                    aliases[n] = other
    return aliases


def error_fields(body):
    """The fields of a variant's body split at its top-level commas."""
    parts, depth, cur = [], 0, ""
    for ch in body:
        if ch in "([{<":
            depth += 1
        elif ch in ")]}>":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    return parts + ([cur] if cur.strip() else [])


def error_says(message, field):
    """Whether an `#[error(...)]` message prints `field` (a name, or a tuple index as text): in the
    format string as `{field}` / `{field:…}`, or among the arguments after it as `.field`."""
    lit = re.match(r'\s*"((?:[^"\\]|\\.)*)"(.*)', message, re.S)
    fmt, args = (lit.group(1), lit.group(2)) if lit else (message, "")
    return (re.search(r"\{%s(:[^}]*)?\}" % field, fmt) is not None
            or re.search(r"\.%s\b" % field, args) is not None)


def printed_and_exposed(text):
    """Line numbers of thiserror variants whose `#[error(...)]` prints the field that is also their
    `source()`: a field marked `#[source]` or `#[from]`, or named `source`. `transparent` is not
    counted (it is the cause, said once), nor a message built by a function (`fmt = ...`)."""
    found = []
    variant = re.compile(r"#\[error\((.*?)\)\]\s*(?:#\[[^\]]*\]\s*)*(\w+)\s*([({])", re.S)
    for m in variant.finditer(text):
        message, opener = m.group(1), m.group(3)
        if message.strip() == "transparent" or message.strip().startswith("fmt"):
            continue
        depth, i = 1, m.end()
        while depth and i < len(text):
            depth += text[i] in "([{<"
            depth -= text[i] in ")]}>"
            i += 1
        fields = error_fields(text[m.end():i - 1])
        for index, field in enumerate(fields):
            marked = re.search(r"#\[(source|from)\]", field) is not None
            if opener == "(":
                name = str(index)
            else:
                named = re.search(r"(\w+)\s*:", re.sub(r"#\[[^\]]*\]|///[^\n]*", "", field))
                if not named:
                    continue
                name = named.group(1)
                marked = marked or name == "source"
            if marked and error_says(message, name):
                found.append(text[:m.start()].count("\n") + 1)
                break
    return found


def main():
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    code = {c: [] for c in CRATES}
    tests = {c: 0 for c in CRATES}
    for c in CRATES:
        for p in rust_files(c):
            k, t = split_code(p)
            code[c].append((p, "\n".join(k)))
            tests[c] += len(t)
    print("root aliases of other crates' modules, and `crate::` paths that lead into another crate:")
    for c in CRATES:
        aliases = root_aliases(c)
        total = into = 0
        for p in rust_files(c):
            text = open(p, errors="replace").read()
            for m in re.finditer(r"\bcrate::(\w+)", text):
                total += 1
                if m.group(1) in aliases:
                    into += 1
        print(f"  {c:10} {len(aliases):3} aliases, {into:4} of {total:4} crate:: paths into another crate")

    print("\ntop-level `pub` items no other crate names (by name, in another crate or in its own tests/, examples/, benches/):")
    # A crate's own integration tests, examples and benches are other crates too.
    all_files = [p for c in CRATES + OUTSIDE for p in rust_files(c)]
    for c in CRATES:
        src = os.path.join(c, "src") + os.sep
        rest = "\n".join(open(p, errors="replace").read() for p in all_files if not p.startswith(src))
        words = set(re.findall(r"\w+", rest))
        pub = unused = 0
        for p, text in code[c]:
            for m in re.finditer(r"^pub (?:fn|struct|enum|const|static|mod|trait|type) (\w+)", text, re.M):
                pub += 1
                if m.group(1) not in words:
                    unused += 1
        print(f"  {c:10} {unused:4} of {pub:4}")

    print("\nnotes and errors as text (non-test code):")
    for c in CRATES:
        pushes = variants = result_string = 0
        for p, text in code[c]:
            pushes += len(re.findall(r"\b\w*(?:warnings|notes|warning|note)\w*\s*\.push\(\s*(?:format!|\"|String::)", text))
            result_string += len(re.findall(r"Result<[^;{]*,\s*String>", text))
            if "thiserror" in text or "#[error(" in text:
                variants += len(re.findall(r"^\s*\w+\((?:pub )?String\),?$|^\s*\w+\s*\{\s*\w+:\s*String\s*\},?$", text, re.M))
        print(f"  {c:10} {pushes:4} String notes pushed, {variants:3} String-only error variants, "
              f"{result_string:3} Result<_, String>")

    print("\nerrors that print and expose their source (a thiserror variant whose message prints the")
    print("field that is its `#[source]`/`#[from]`/`source`; non-test code; `python/` too):")
    for c in CRATES + ["python"]:
        n = sum(len(printed_and_exposed(text)) for p in rust_files(c) for text in ["\n".join(split_code(p)[0])]
                if text)
        print(f"  {c:10} {n:4}")

    print("\ncommand-line flag names in string literals below the command line (non-test code; a")
    print("literal may run over lines; comments and char literals are left out before reading):")
    for c in BELOW_EDGE:
        flags = set()
        for p, text in code[c]:
            # Comments first (a doc comment's quotes would pair with a literal's), then char
            # literals such as '"'.
            bare = re.sub(r"^\s*//.*$", "", text, flags=re.M)
            bare = re.sub(r"'(?:\\.|[^'\\])'", "''", bare)
            for s in re.findall(r"\"(?:[^\"\\]|\\.)*\"", bare, re.S):
                flags.update(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]+", s))
        print(f"  {c:10} {len(flags):4} distinct flags{': ' + ' '.join(sorted(flags)) if flags else ''}")

    print("\nlines of code and of tests per crate:")
    for c in CRATES:
        n = sum(t.count("\n") + 1 for _, t in code[c] if t)
        print(f"  {c:10} {n:6} code, {tests[c]:6} test ({tests[c] / max(n, 1):.1f}x)")


if __name__ == "__main__":
    sys.exit(main())
