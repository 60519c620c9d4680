#!/usr/bin/env python3
"""Checks the one error convention at layer boundaries (issue #30 item 3, src/util/error.hpp).

Two kinds of site fail unless allowed in the allow-list, each entry with its reason:
  out-param  a function declared in a header under src/ (but src/codec, which keeps CodecError)
             that reports failure through a `std::string& error` / `std::string* error` /
             `std::string& why` parameter: it returns an Error or a Result<T> instead;
  throw      a `throw` in a file under src/: exceptions live only where a parse must throw (a
             library that throws, a reader that unwinds from deep inside a document), caught at
             that layer's edge.
Allow-list lines: `out-param <header>:<function>  # reason` or `throw <file>  # reason`. An
entry that no longer matches a site fails too (STALE), so the list only shrinks."""
import re
import sys
from pathlib import Path

OUT_PARAM = re.compile(r"(?<!const )std::string\s*[&*]\s*(error|err|why)\b")  # const: an input
THROW = re.compile(r"\bthrow\b")
IDENT_BEFORE_PAREN = re.compile(r"([~\w]+)\s*$")


def code_only(text):
    """The text with comments and string/char literals blanked (lengths kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + (c if j < n else ""))
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def function_of(code, pos):
    """The name of the function whose parameter list holds `pos`; None outside one."""
    depth = 0
    for i in range(pos, -1, -1):
        if code[i] == ")":
            depth += 1
        elif code[i] == "(":
            if depth == 0:
                m = IDENT_BEFORE_PAREN.search(code[:i])
                return m.group(1) if m else "?"
            depth -= 1
    return None


def sites(src):
    found = {}  # key -> first line
    for path in sorted(src.rglob("*")):
        if path.suffix not in (".hpp", ".cpp") or not path.is_file():
            continue
        rel = str(path.relative_to(src.parent))
        code = code_only(path.read_text(encoding="utf-8", errors="replace"))
        if path.suffix == ".hpp" and not rel.startswith("src/codec/"):
            for m in OUT_PARAM.finditer(code):
                function = function_of(code, m.start())
                if function is None or code[m.end():].lstrip().startswith("("):
                    continue  # a member `std::string& error()`, not a parameter
                key = f"out-param {rel}:{function}"
                found.setdefault(key, code.count("\n", 0, m.start()) + 1)
        for m in THROW.finditer(code):
            found.setdefault(f"throw {rel}", code.count("\n", 0, m.start()) + 1)
    return found


def main():
    src, allow_file = Path(sys.argv[1]), Path(sys.argv[2])
    allowed = {}
    for raw in allow_file.read_text().splitlines():
        entry = raw.split("#", 1)[0].strip()
        if entry:
            allowed[" ".join(entry.split())] = raw.split("#", 1)[1].strip() if "#" in raw else ""
    found = sites(src)
    bad = sorted(k for k in found if k not in allowed)
    stale = sorted(set(allowed) - set(found))
    unexplained = sorted(k for k, why in allowed.items() if not why)
    for k in sorted(found):
        print(f"{'allowed' if k in allowed else 'FAILS':8} {k} (line {found[k]})")
    for k in stale:
        print(f"STALE    allow-list entry matches no site any more: {k}")
    for k in unexplained:
        print(f"NO WHY   allow-list entry without a reason: {k}")
    if bad:
        print("A function that can fail returns mbstorm::Error or Result<T> (src/util/error.hpp); "
              "docs/architecture.md, \"Errors\".")
    return 1 if bad or stale or unexplained else 0


if __name__ == "__main__":
    sys.exit(main())
