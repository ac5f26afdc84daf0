#!/usr/bin/env python3
"""The code's shape, checked: layers include only the layers below them, no non-test source file
is longer than 700 lines, no function in non-test code is longer than 120 lines, and no tracked
file speaks of the rounds of work that produced it ("session" and a number).

    structure_test.py ROOT            check, print one line per violation, exit 1 if any
    structure_test.py ROOT --layers   also print the include counts between folders
"""
import pathlib
import re
import subprocess
import sys

MAX_FILE_LINES = 700
MAX_FUNCTION_LINES = 120

# Folders from the bottom up; a folder may include itself and any folder before it in its column.
# The two processes never include each other; the render client's tools and baselines sit on it.
LAYERS = {
    "common": [],
    "common/scene": ["common"],
    "common/lod": ["common", "common/scene"],
    "common/setup": ["common", "common/scene", "common/lod"],
    "common/cull": ["common", "common/scene", "common/lod"],
    "common/gl": ["common", "common/scene", "common/lod", "common/setup", "common/cull"],
    "common/fuzz": ["common", "common/scene", "common/lod", "common/setup", "common/cull"],
    "protocol": ["common"],
    "protocol/net": ["common", "protocol"],
    "protocol/relay": ["common", "protocol", "protocol/net"],
    "protocol/bench": ["common", "protocol", "protocol/net"],
    "protocol/fuzz": ["common", "protocol", "protocol/net"],
    "protocol/cluster": ["common", "common/scene", "common/lod", "common/setup", "common/cull", "protocol",
                         "protocol/net"],
}
_ALL_BELOW_PROCESSES = list(LAYERS)
LAYERS["switch_node"] = _ALL_BELOW_PROCESSES
LAYERS["render_client"] = _ALL_BELOW_PROCESSES
PROCESS_PARTS = {"switch_node": ["switch_node"], "render_client": ["render_client"]}


def unit_of(path: str) -> str:
    """The layer a source file belongs to: its folder, with a process's sub-folders folded in."""
    folder = str(pathlib.PurePosixPath(path).parent)
    for process in PROCESS_PARTS:
        if folder == process or folder.startswith(process + "/"):
            return process
    return folder


def strip_comments_and_strings(src: str) -> str:
    """The source with comments, string and character literals blanked (line breaks kept)."""
    out, i, n = [], 0, len(src)
    blank = lambda s: re.sub(r"[^\n]", " ", s)
    while i < n:
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
        elif src.startswith("/*", i):
            j = src.find("*/", i + 2)
            j = n if j < 0 else j + 2
        elif src.startswith('R"', i) and (m := re.match(r'R"([^(]*)\(', src[i:])):
            end = ")" + m.group(1) + '"'
            j = src.find(end, i)
            j = n if j < 0 else j + len(end)
        elif src[i] in "\"'" and not (src[i] == "'" and i > 0 and src[i - 1].isalnum()):
            j = i + 1
            while j < n and src[j] != src[i] and src[j] != "\n":
                j += 2 if src[j] == "\\" else 1
            j += 1
        else:
            out.append(src[i])
            i += 1
            continue
        out.append(blank(src[i:j]))
        i = j
    return "".join(out)


FUNCTION_HEAD = re.compile(r"\)\s*(const|noexcept|override|final|mutable|->\s*[\w:<>,\s*&]+|\s)*$")
CONTROL_HEAD = re.compile(r"\b(if|for|while|switch|catch)\s*\([^;{}]*\)\s*$")


def long_functions(src: str, limit: int):
    """(first line, last line, name) of each outermost function body longer than `limit` lines.
    Lambdas and local blocks count toward the function that holds them."""
    code = strip_comments_and_strings(src)
    stack = []  # (offset of '{', opens a function body)
    for m in re.finditer(r"[{}]", code):
        if m.group() == "{":
            head = code[max(0, m.start() - 300):m.start()]
            stack.append((m.start(), bool(FUNCTION_HEAD.search(head)) and not CONTROL_HEAD.search(head)))
            continue
        if not stack:
            continue
        start, is_function = stack.pop()
        if not is_function or any(f for _, f in stack):
            continue
        first = code.count("\n", 0, start) + 1
        last = code.count("\n", 0, m.start()) + 1
        if last - first + 1 > limit:
            names = re.findall(r"([\w:~]+)\s*\(", code[max(0, start - 300):start])
            yield first, last, names[-1] if names else "?"


def main() -> int:
    root = pathlib.Path(sys.argv[1])
    files = subprocess.run(["git", "-C", str(root), "ls-files"], capture_output=True, text=True,
                           check=True).stdout.split()
    errors, edges = [], {}
    sources = [f for f in files if f.endswith((".cpp", ".hpp")) and not f.startswith("tests/")]
    for f in sources:
        text = (root / f).read_text(encoding="utf-8")
        lines = text.count("\n")
        if lines > MAX_FILE_LINES:
            errors.append(f"{f}: {lines} lines (at most {MAX_FILE_LINES}: split it by concept)")
        for first, last, name in long_functions(text, MAX_FUNCTION_LINES):
            errors.append(f"{f}:{first}: {name} is {last - first + 1} lines (at most {MAX_FUNCTION_LINES})")
        unit = unit_of(f)
        includes = [(i + 1, m.group(1)) for i, line in enumerate(text.splitlines())
                    if (m := re.match(r'\s*#\s*include\s+"([^"]+)"', line))]
        for n, target in includes:
            if "/" not in target:
                continue  # a file beside this one
            to = unit_of(target)
            edges[(unit, to)] = edges.get((unit, to), 0) + 1
            if unit not in LAYERS:
                errors.append(f"{f}: folder {unit} is not in the layer table (tests/structure_test.py LAYERS)")
                break
            if to == unit:
                continue
            if to not in LAYERS[unit]:
                errors.append(f"{f}:{n}: {unit} includes {target}, a layer it must not use ({to})")
    if "--layers" in sys.argv:
        for (a, b), count in sorted(edges.items()):
            if a != b:
                print(f"{a} -> {b}: {count}")
    for e in errors:
        print(e)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
