#!/usr/bin/env python3
"""Lists the C++ functions longer than a limit (default 120 lines), longest first.

    scripts/long_functions.py [--max 120] [PATH ...]      (default paths: lib apps)

A function's length is counted from the first line of its signature to its closing brace, lambdas and
blank lines inside it included. The scan matches braces after removing comments, string and character
literals (raw strings too); a brace opens a function body when the text before it, back to the last
`;`, `{` or `}`, has a parameter list and is not a namespace, class, struct, enum, union or
initializer. Functions inside a function (local classes) count as part of it. Exit code 1 when any
function is over the limit, so that it can gate CI; 0 otherwise.
"""
import argparse
import pathlib
import re
import sys

_NOT_A_FUNCTION = re.compile(r"^\s*(?:template\s*<.*>\s*)?(namespace|class|struct|enum|union|extern)\b",
                             re.S)
_MEMBER_INIT = re.compile(r"\)\s*(?:noexcept\s*)?:(?!:)")


def strip_code(text):
    """The text with comments and literals replaced by spaces (newlines kept, so lines still count)."""
    out = []
    i, n = 0, len(text)
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
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^()\\ ]{0,16})\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i + m.end())
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            # A digit separator (1'000'000) is no character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "#" and (i == 0 or text[i - 1] == "\n" or text[: i].rsplit("\n", 1)[-1].strip() == ""):
            # A preprocessor line (with its continuations).
            j = i
            while True:
                k = text.find("\n", j)
                if k < 0:
                    k = n
                    break
                if text[k - 1] != "\\":
                    break
                j = k + 1
            out.append(re.sub(r"[^\n]", " ", text[i:k]))
            i = k
        else:
            out.append(c)
            i += 1
    return "".join(out)


def function_name(header):
    """The name before the parameter list of a function header (`ns::Type::name`, `operator()`)."""
    depth = 0
    for k, ch in enumerate(header):
        if ch in "<[":
            depth += 1
        elif ch in ">]":
            depth = max(0, depth - 1)
        elif ch == "(" and depth == 0:
            before = header[:k].rstrip()
            if before.endswith("operator"):
                return before.split()[-1] + "()"
            m = re.search(r"((?:[A-Za-z_~][\w]*\s*::\s*)*(?:operator\s*\S+|[A-Za-z_~]\w*))\s*$", before)
            return re.sub(r"\s+", "", m.group(1)) if m else "?"
    return "?"


def functions(path):
    """(name, first line, last line) of every function defined at namespace or class scope."""
    text = strip_code(path.read_text(encoding="utf-8", errors="replace"))
    line_of = [0] * (len(text) + 1)
    line = 1
    for k, ch in enumerate(text):
        line_of[k] = line
        if ch == "\n":
            line += 1
    stack = []  # each open brace: ("function", start offset, name) or ("scope", ...) or ("other", ...)
    last_end = 0  # offset after the last ; { } at the current scope
    found = []
    for k, ch in enumerate(text):
        if ch == "{":
            # Inside a function or an initializer every brace is part of it.
            nested = any(kind != "scope" for kind, _, _ in stack)
            header = text[last_end:k]
            stripped = header.strip()
            kind = "other"
            if not nested:
                before_params = re.sub(r"operator\s*\S+", "operator", stripped).split("(", 1)[0]
                if _NOT_A_FUNCTION.match(stripped):
                    kind = "scope"
                elif _MEMBER_INIT.search(stripped) and re.search(r"[\w>]$", stripped):
                    # `Type::Type(..) : member_{value}`: a member's brace initializer, the header goes on.
                    stack.append(("init", k, ""))
                    continue
                elif "(" in stripped and ")" in stripped and "=" not in before_params:
                    kind = "function"
            start = last_end + (len(header) - len(header.lstrip()))
            stack.append((kind, start, function_name(stripped) if kind == "function" else ""))
            last_end = k + 1
        elif ch == "}":
            if stack:
                kind, start, name = stack.pop()
                if kind == "init":
                    continue
                if kind == "function":
                    found.append((name, line_of[start], line_of[k]))
            last_end = k + 1
        elif ch == ";":
            last_end = k + 1
        elif ch == ":" and stack and stack[-1][0] == "scope":
            # `public:` and friends end a class's previous declaration.
            before = text[last_end:k].strip()
            if before in ("public", "private", "protected"):
                last_end = k + 1
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--max", type=int, default=120, help="longest allowed, in lines (default 120)")
    parser.add_argument("paths", nargs="*", default=["lib", "apps"])
    args = parser.parse_args()
    rows = []
    for root in args.paths:
        p = pathlib.Path(root)
        files = [p] if p.is_file() else sorted(
            f for f in p.rglob("*") if f.suffix in (".cpp", ".cc", ".h", ".hpp"))
        for f in files:
            for name, first, last in functions(f):
                length = last - first + 1
                if length > args.max:
                    rows.append((length, f"{f}:{first}", name))
    for length, where, name in sorted(rows, key=lambda r: (-r[0], r[1])):
        print(f"{length:5d}  {where}  {name}")
    if rows:
        print(f"{len(rows)} function(s) over {args.max} lines", file=sys.stderr)
    return 1 if rows else 0


if __name__ == "__main__":
    sys.exit(main())
