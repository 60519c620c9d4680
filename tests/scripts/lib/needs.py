#!/usr/bin/python3
"""Checks that scripts/test-needs.txt covers every program and python module the test and
benchmark scripts use, so that scripts/setup.sh (which installs and verifies that list) is
enough for them.

Usage: needs.py SOURCE_ROOT
Prints each use that the list does not cover (file, name) and exits 1; exits 0 otherwise.

Programs are the words in command position of each shell script, read from bash's own
parser (`bash --pretty-print`, which drops comments and puts heredocs on their own lines):
builtins, keywords, the scripts' own functions and project binaries (run through a variable
or a relative path) are not needs. Modules are the non-standard-library imports of the python
scripts and of `python3 -c` one-liners. A shell heuristic, not a full parser: it errs towards
reporting more, never fewer."""
import ast
import pathlib
import re
import subprocess
import sys

SHELL_SCRIPTS = ["tests/scripts/*.sh", "tests/scripts/lib/*.bash", "bench/*.sh", "bench/lib/*.bash",
                 "scripts/test-all.sh", "scripts/run-fuzz.sh", "scripts/bench-smoke.sh", "scripts/deb-check.sh"]
PYTHON_SCRIPTS = ["tests/scripts/*.py", "tests/scripts/lib/*.py", "bench/peers/*.py"]

BUILTINS = set("""
[ [[ ]] test echo printf read local declare typeset export set unset shift source . trap exit
return wait kill cd pwd eval exec ulimit mapfile readarray type true false break continue let
getopts shopt pushd popd umask times alias hash jobs disown fg bg builtin enable caller
compgen complete : command
""".split())
KEYWORDS = set("if then else elif fi for while until do done case esac in function select time ! coproc".split())
# Wrappers whose argument is itself a command, with how many option words they take.
WRAPPERS = {"timeout": re.compile(r"^(-\S+|\d+(\.\d+)?[smhd]?|\$\S+|Q)$"), "taskset": re.compile(r"^(-\S+|[0-9a-fx,-]+)$"),
            "nice": re.compile(r"^-\S+$"), "env": re.compile(r"^(-\S+|\w+=\S*)$")}


def read_needs(root):
    programs, modules = set(), set()
    for line in (root / "scripts/test-needs.txt").read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        kind, name = words[0], words[1]
        if kind == "program":
            programs.add(name)
        elif kind == "module":
            modules.add(name)
    return programs, modules


def drop_heredocs(text):
    out, end = [], None
    for line in text.splitlines():
        if end is not None:
            if line.strip() == end:
                end = None
            continue
        m = re.search(r"<<-?\s*['\"]?(\w+)['\"]?", line.replace("<<<", ""))
        if m:
            end = m.group(1)
        out.append(line)
    return "\n".join(out)


def flatten(text):
    """Quoted text becomes Q; command substitutions, subshells and process substitutions
    become separate commands (separated by ';'); arithmetic and array literals vanish."""
    out, stack, i = [], ["cmd"], 0
    while i < len(text):
        c, ctx = text[i], stack[-1]
        two, three = text[i:i + 2], text[i:i + 3]
        if ctx in ("dq", "param", "array"):
            if c == "\\":
                i += 2
                continue
            if two == "$(" and three != "$((":
                stack.append("cmd")
                out.append(" ; ")
                i += 2
                continue
            if (ctx == "dq" and c == '"') or (ctx == "param" and c == "}") or (ctx == "array" and c == ")"):
                stack.pop()
            elif c == '"' and ctx != "dq":
                stack.append("dq")
            elif two == "${":
                stack.append("param")
                i += 1
            i += 1
            continue
        if ctx == "arith":
            if two == "))":
                stack.pop()
                i += 2
                continue
            i += 1
            continue
        # command context
        if c == "\\":
            out.append(" ")
            i += 2
        elif c == "'":
            j = text.index("'", i + 1)
            out.append("Q")
            i = j + 1
        elif c == '"':
            stack.append("dq")
            out.append("Q")
            i += 1
        elif three == "$((" or two == "((":
            stack.append("arith")
            out.append(" Q ")
            i += 3 if three == "$((" else 2
        elif two in ("$(", "<(", ">("):
            stack.append("cmd")
            out.append(" ; ")
            i += 2
        elif two == "${":
            stack.append("param")
            out.append("Q")
            i += 2
        elif two == "=(":
            stack.append("array")
            out.append("=Q")
            i += 2
        elif c == "(":
            stack.append("cmd")
            out.append(" ; ")
            i += 1
        elif c == ")":
            if len(stack) > 1:
                stack.pop()
                out.append(" ; ")
            else:  # a case pattern: what precedes it on the line is not a command
                k = len(out)
                while k > 0 and "\n" not in out[k - 1] and ";" not in out[k - 1]:
                    k -= 1
                del out[k:]
                out.append(" ; ")
            i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def commands(text):
    flat = flatten(drop_heredocs(text))
    flat = re.sub(r"\d*&?(>>|>\||>&|<>|<<<|<<-?|>|<)\s*(&?-?\d+\b|[^\s;|&()]+)?", " ", flat)
    for segment in re.split(r"[;|&\n{}]", flat):
        words = segment.split()
        while words and (words[0] in KEYWORDS or re.match(r"^\w+(\[[^]]*\])?\+?=", words[0])):
            if words[0] in ("for", "case", "select"):
                words = []
                break
            words = words[1:]
        while words:
            first = words[0]
            if first == "command" and len(words) > 2 and words[1] == "-v":
                yield words[2]
                break
            if first in WRAPPERS:
                yield first
                rest = words[1:]
                while rest and WRAPPERS[first].match(rest[0]):
                    rest = rest[1:]
                words = rest
                continue
            if first == "exec":
                words = words[1:]
                continue
            yield first
            break


def program_name(word, functions):
    if word in BUILTINS or word in KEYWORDS or word in functions or word.startswith(("Q", "$", "-")):
        return None
    if "/" in word:  # only system paths name a program; others are the project's own binaries
        return word.rsplit("/", 1)[1] if re.match(r"^/(usr/)?s?bin/", word) else None
    if not re.match(r"^[\w.+-]+$", word):
        return None
    return word


def python_imports(source):
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            yield from (a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            yield node.module


def main(root):
    programs, modules = read_needs(root)
    shells = sorted({p for g in SHELL_SCRIPTS for p in root.glob(g)})
    pythons = sorted({p for g in PYTHON_SCRIPTS for p in root.glob(g)})
    problems, checked = [], 0
    functions = set()
    parsed = {}
    for path in shells:
        text = subprocess.run(["bash", "--pretty-print", str(path)], check=True, capture_output=True,
                              text=True).stdout
        parsed[path] = text
        functions.update(re.findall(r"^\s*([\w-]+)\s*\(\)", text, re.M))
    for path, text in parsed.items():
        for word in commands(text):
            name = program_name(word, functions)
            if name is None:
                continue
            checked += 1
            if name not in programs:
                problems.append(f"{path.relative_to(root)}: runs program '{name}'")
        # `python3 -c '...'` one-liners: their imports.
        for line in path.read_text().splitlines():
            if "python3" in line:
                for m in re.finditer(r"\bimport ([\w.]+(?:\s*,\s*[\w.]+)*)|\bfrom ([\w.]+) import", line):
                    for mod in (m.group(1) or m.group(2)).split(","):
                        check_module(mod.strip(), path, root, modules, problems)
    for path in pythons:
        for mod in python_imports(path.read_text()):
            checked += 1
            check_module(mod, path, root, modules, problems)
    for p in problems:
        print(f"{p}: not in scripts/test-needs.txt (add it there with its Debian package)")
    print(f"{len(shells)} shell and {len(pythons)} python scripts, {checked} uses checked, "
          f"{len(problems)} not covered")
    return 1 if problems else 0


def check_module(mod, path, root, modules, problems):
    if mod.split(".")[0] in sys.stdlib_module_names:
        return
    if mod not in modules:
        problems.append(f"{path.relative_to(root)}: imports python module '{mod}'")


if __name__ == "__main__":
    sys.exit(main(pathlib.Path(sys.argv[1]).resolve()))
