#!/usr/bin/env python3
"""Docs checks, on the repository at argv[1].

Default: the README is a user guide: at most 200 lines, no path that leaves the repository, and
every relative link in README.md and docs/*.md names a file that exists.
--no-session-numbers: no file of the repository mentions "session" followed by a number (docs and
comments state facts with their command, date and commit, not the round of work that found them);
build and output folders (build*, out) and .git are skipped."""
import os
import pathlib
import re
import sys


def readme_is_a_guide(root):
    errors = []
    readme = (root / "README.md").read_text(encoding="utf-8")
    lines = readme.count("\n")
    if lines > 200:
        errors.append(f"README.md: {lines} lines, a user guide keeps to 200 (move results to docs/)")
    for n, line in enumerate(readme.splitlines(), 1):
        if re.search(r"(^|[\s`(])\.\./", line):
            errors.append(f"README.md:{n}: a path outside the repository: {line.strip()}")
    for doc in [root / "README.md", *sorted((root / "docs").glob("*.md"))]:
        for n, line in enumerate(doc.read_text(encoding="utf-8").splitlines(), 1):
            for target in re.findall(r"\]\(([^)#\s]+)[^)]*\)", line):
                if re.match(r"[a-z]+:", target):
                    continue  # a URL
                if not (doc.parent / target).exists():
                    errors.append(f"{doc.relative_to(root)}:{n}: link to a missing file: {target}")
    return errors


def repository_files(root):
    """Every file under root but build and output folders (build*, out) and .git."""
    for folder, dirs, files in os.walk(root):
        if pathlib.Path(folder) == root:
            dirs[:] = [d for d in dirs if d != ".git" and not d.startswith("build") and d != "out"]
        for name in sorted(files):
            yield pathlib.Path(folder) / name


def no_session_numbers(root):
    errors = []
    pattern = re.compile(r"session [0-9]+", re.IGNORECASE)
    for path in sorted(repository_files(root)):
        data = path.read_bytes()
        if b"\0" in data[:8192]:
            continue  # binary (images)
        for n, line in enumerate(data.decode("utf-8", errors="replace").splitlines(), 1):
            m = pattern.search(line)
            if m:
                errors.append(f"{path.relative_to(root)}:{n}: names a round of work ('{m.group(0)}'): state the "
                              f"fact with its command, date and commit instead: {line.strip()[:120]}")
    return errors


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    root = pathlib.Path(args[0])
    errors = no_session_numbers(root) if "--no-session-numbers" in sys.argv else readme_is_a_guide(root)
    for e in errors:
        print(e)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
