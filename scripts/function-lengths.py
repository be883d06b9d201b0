#!/usr/bin/env python3
"""Lists the C++ functions in a tree longer than a limit, and fails when there is one.

    scripts/function-lengths.py [--max N] [--top K] [DIR...]     (default: --max 120 src)

A function is a brace block opened at namespace or class scope right after a parameter list
(`) {`, `) const {`, `) : m_a(a) {` ...); its length counts its lines from the line of its name
to its closing brace, lambdas and local classes inside it included. Comments, strings and
character literals are blanked first so that braces in them do not count. Exits 1 naming each
function over the limit (file:line, length, name), 0 when none is; `--top K` also lists the K
longest. Run by ctest `Style.function_length` (label style).
"""
import argparse
import pathlib
import re
import sys

SOURCE_SUFFIXES = {".cpp", ".h", ".hpp", ".cc", ".inl"}


def blank_comments_and_strings(text):
    """The text with comments, string and character literals replaced by spaces (newlines kept)."""
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
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            # A digit separator (1'000'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum() \
                    and re.match(r"[0-9a-fA-F]", text[i - 1]):
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * max(0, j - i - 2) + (c if j - i >= 2 else ""))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def blank_preprocessor(text):
    """Preprocessor lines (with their continuations) as blank lines."""
    lines = text.split("\n")
    out, continued = [], False
    for line in lines:
        directive = continued or line.lstrip().startswith("#")
        out.append("" if directive else line)
        continued = directive and line.rstrip().endswith("\\")
    return "\n".join(out)


# What may stand between a parameter list's `)` and the body's `{`: qualifiers, a trailing
# return type, or a constructor's member initialisers (which the scan below skips as a unit).
QUALIFIERS = re.compile(r"^(?:\s|const\b|noexcept\b|override\b|final\b|mutable\b|&|->\s*[\w:<>,\s*&]+)*$")


def function_blocks(code):
    """(name, first line, last line) of each function body at namespace or class scope."""
    blocks = []
    # Stack of open braces: each entry is True when the block is a scope that can hold functions
    # (namespace, class, struct, extern "C", top level), False inside a function or initialiser.
    stack = []
    line_of = [0] * (len(code) + 1)
    line = 1
    for k, ch in enumerate(code):
        line_of[k] = line
        if ch == "\n":
            line += 1
    line_of[len(code)] = line
    i, n = 0, len(code)
    open_functions = []  # (stack depth, name, first line)
    while i < n:
        ch = code[i]
        if ch == "{":
            scope_level = all(stack)
            kind = classify_block(code, i) if scope_level else "other"
            if kind[0] == "function":
                open_functions.append((len(stack), kind[1], line_of[kind[2]]))
                stack.append(False)
            else:
                stack.append(kind[0] == "scope")
        elif ch == "}":
            if stack:
                stack.pop()
            if open_functions and open_functions[-1][0] == len(stack):
                depth, name, first = open_functions.pop()
                blocks.append((name, first, line_of[i]))
        i += 1
    return blocks


def classify_block(code, brace):
    """('function', name, start offset) when the `{` at `brace` opens a function body; ('scope',)
    for namespaces, classes, structs, unions and extern blocks; ('other',) otherwise (brace
    initialisers, enums, array initialisers)."""
    head_start = max(code.rfind(";", 0, brace), code.rfind("}", 0, brace), code.rfind("{", 0, brace)) + 1
    head = code[head_start:brace]
    stripped = head.strip()
    if re.search(r"\b(namespace|extern)\b", stripped) and "(" not in stripped.split("namespace")[-1]:
        return ("scope",)
    if re.search(r"\b(class|struct|union)\b", stripped) and not stripped.endswith(")") and "(" not in stripped:
        return ("scope",)
    if re.search(r"\benum\b", stripped):
        return ("other",)
    if not stripped or stripped.endswith("=") or stripped.endswith(","):
        return ("other",)
    # Find the parameter list: the last top-level `( ... )` before the qualifiers, or, for a
    # constructor, the one before its `:` initialiser list.
    close = find_parameter_list_end(head)
    if close < 0:
        return ("other",)
    open_paren = matching_open(head, close)
    if open_paren < 0:
        return ("other",)
    before = head[:open_paren].rstrip()
    m = re.search(r"(operator\s*[^\s(]+|~?[A-Za-z_]\w*(?:\s*::\s*~?[A-Za-z_]\w*)*)\s*(?:<[^()]*>)?$", before)
    if not m:
        return ("other",)
    name = re.sub(r"\s+", "", m.group(1))
    if name in {"if", "for", "while", "switch", "catch", "return", "sizeof", "decltype", "alignas"}:
        return ("other",)
    start = head_start + m.start(1)
    # The signature's first line: back to the start of the declaration (return type, template).
    decl_start = head_start + (len(head) - len(head.lstrip()))
    return ("function", name, min(start, decl_start))


def find_parameter_list_end(head):
    """Index of the `)` that closes the parameter list in a function head, or -1."""
    # Constructor initialiser list: `) : a(x), b{y} {` -> the `)` before the top-level ` : `.
    depth = 0
    for k, ch in enumerate(head):
        if ch in "([<":
            depth += 1 if ch != "<" else 0
        if ch in ")]":
            depth -= 1
        if ch == ":" and depth == 0:
            prev = head[k - 1] if k > 0 else ""
            nxt = head[k + 1] if k + 1 < len(head) else ""
            if prev != ":" and nxt != ":":
                j = head.rfind(")", 0, k)
                if j >= 0 and QUALIFIERS.match(head[j + 1:k]):
                    return j
                return -1
    j = head.rfind(")")
    if j >= 0 and QUALIFIERS.match(head[j + 1:]):
        return j
    return -1


def matching_open(text, close):
    depth = 0
    for k in range(close, -1, -1):
        if text[k] == ")":
            depth += 1
        elif text[k] == "(":
            depth -= 1
            if depth == 0:
                return k
    return -1


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dirs", nargs="*", default=["src"])
    parser.add_argument("--max", type=int, default=120, help="longest allowed function, in lines")
    parser.add_argument("--top", type=int, default=0, help="also list the K longest functions")
    args = parser.parse_args()
    found = []
    for d in args.dirs:
        root = pathlib.Path(d)
        if not root.exists():
            print(f"function-lengths: {d}: no such file or folder", file=sys.stderr)
            return 2
        files = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.suffix in SOURCE_SUFFIXES)
        for path in files:
            code = blank_preprocessor(blank_comments_and_strings(path.read_text(encoding="utf-8", errors="replace")))
            for name, first, last in function_blocks(code):
                found.append((last - first + 1, str(path), first, name))
    found.sort(key=lambda f: (-f[0], f[1], f[2]))
    for length, path, first, name in found[: args.top]:
        print(f"{length:5d}  {path}:{first}  {name}")
    too_long = [f for f in found if f[0] > args.max]
    for length, path, first, name in too_long:
        print(f"{path}:{first}: function '{name}' is {length} lines (at most {args.max}: split it into named steps)",
              file=sys.stderr)
    if too_long:
        return 1
    print(f"function-lengths: {len(found)} functions, none over {args.max} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main())
