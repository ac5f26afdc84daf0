#!/usr/bin/env python3
"""The README is a user guide: at most 200 lines, no path that leaves the repository, and every
relative link in README.md and docs/*.md names a file that exists."""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1])
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
for e in errors:
    print(e)
sys.exit(1 if errors else 0)
