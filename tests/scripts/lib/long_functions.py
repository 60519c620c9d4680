#!/usr/bin/env python3
"""Lists the functions in src/ longer than a limit (issue #30: none over 100 lines).

The sources are clang-formatted (script.sources_are_formatted), so a function definition at
namespace scope starts on a line at column 0 whose last character is '{' and that is not a
namespace, class, struct, enum or union, and ends at the next line that is a lone '}' at column
0; a member function defined inside a class body is indented and short by the house rules, and
is not counted. A function's length is its body: the lines between its braces."""
import re
import sys
from pathlib import Path

NOT_A_FUNCTION = re.compile(r"^(namespace|class|struct|enum|union|extern|template\s*<[^>]*>\s*(class|struct))\b")


def name_of(lines, last):
    """The function's name: the identifier before '(' on its signature's first line."""
    for i in range(last, max(-1, last - 6), -1):
        line = lines[i]
        if line and not line[0].isspace() and "(" in line:
            return re.findall(r"[\w:~<>=!+\-*/\[\]]+(?=\()", line)[0]
    return lines[last]


def functions(path):
    """(name, first line, body lines) of each definition at column 0."""
    lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    opened = None
    for i, line in enumerate(lines):
        if opened is None:
            if line and not line[0].isspace() and line.rstrip().endswith("{") and ")" in line \
                    and not NOT_A_FUNCTION.match(line) and not line.startswith(("#", "//")):
                opened = i
            elif line.startswith("    ") and line.rstrip().endswith("{") and ")" in line \
                    and i > 0 and lines[i - 1] and not lines[i - 1][0].isspace() \
                    and lines[i - 1].rstrip().endswith((",", "(")):
                opened = i  # the last line of a signature that spans several
        elif line == "}":
            yield name_of(lines, opened), opened + 1, i - opened - 1
            opened = None


def main():
    root, limit, allow_file = Path(sys.argv[1]), int(sys.argv[2]), Path(sys.argv[3])
    allowed = {}
    for raw in allow_file.read_text().splitlines():
        entry = raw.split("#", 1)[0].strip()
        if entry:
            allowed[entry] = raw.split("#", 1)[1].strip() if "#" in raw else ""
    long_ones = []
    for path in sorted(root.rglob("*.cpp")):
        for name, line, length in functions(path):
            if length > limit:
                long_ones.append((f"{path.relative_to(root.parent)}:{name}", line, length))
    bad = [(k, line, n) for k, line, n in long_ones if k not in allowed]
    stale = sorted(set(allowed) - {k for k, _, _ in long_ones})
    for k, line, n in long_ones:
        mark = "allowed" if k in allowed else "TOO LONG"
        print(f"{mark:8} {n:4} lines  {k} (line {line})")
    for k in stale:
        print(f"STALE    allow-list entry no longer over {limit} lines: {k}")
    return 1 if bad or stale else 0


if __name__ == "__main__":
    sys.exit(main())
