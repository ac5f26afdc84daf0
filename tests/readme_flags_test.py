#!/usr/bin/env python3
"""README's flag tables agree with the programs' --help.

Usage: readme_flags_test.py REPO_ROOT RENDER_CLIENT SWITCH_NODE

A flag table is a Markdown table of README.md whose first header cell is `flag`. Each row's first
cell names a flag in backticks, optionally with its values (`--gl auto\\|egl\\|osmesa`). A row that
says "(cluster.sh" (e.g. "(cluster.sh, root)") belongs to scripts/cluster.sh; the others to render_client and switch_node
(cluster.sh passes each flag to the processes that use it). For every row:
- the flag appears in the --help of the program it belongs to (for the binaries: in at least one);
- each value README lists is one the --help lists for that flag;
- a default README states (written "default `X`") equals the default every --help that has the
  flag prints; a row that says "default" must write it that way, so that it can be checked.
The checker first runs on a made-up README and --help, to show that it finds each kind of mismatch.
"""
import pathlib
import re
import subprocess
import sys

BINARY_OPTION = re.compile(r"^\s{2}(--[\w-]+)(?:\s+(\S+))?")
HELP_DEFAULT = re.compile(r"\(default ([^()]*)\)\s*$")
README_DEFAULT = re.compile(r"default `([^`]+)`")


def split_row(line):
    """The cells of a Markdown table row; `\\|` inside a cell stays a literal bar."""
    cells = re.split(r"(?<!\\)\|", line.strip().strip("|"))
    return [c.strip().replace("\\|", "|") for c in cells]


def readme_flag_rows(readme):
    """(line number, flag, README's values or None, default or None, says default, cluster.sh) per row."""
    rows = []
    in_flag_table = False
    for n, line in enumerate(readme.splitlines(), 1):
        if not line.startswith("|"):
            in_flag_table = False
            continue
        cells = split_row(line)
        if cells and cells[0] == "flag":
            in_flag_table = True
            continue
        if not in_flag_table or set(cells[0]) <= set("-: "):
            continue
        m = re.match(r"`(--[\w-]+)(?:\s+([^`]+))?`", cells[0])
        if not m:
            rows.append((n, cells[0], None, None, False, False))
            continue
        flag, arg = m.group(1), m.group(2)
        values = arg.split("|") if arg and "|" in arg else None
        text = " ".join(cells[1:])
        d = README_DEFAULT.search(text)
        rows.append((n, flag, values, d.group(1) if d else None,
                     re.search(r"\bdefault\b", text) is not None, re.search(r"\(cluster\.sh\b", text) is not None))
    return rows


def binary_options(help_text):
    """flag -> (values or None, default or None) from a binary's --help: one option a line, starting
    `  --flag`, its text possibly going on in lines indented further."""
    options = {}
    current = None
    for line in help_text.splitlines():
        m = BINARY_OPTION.match(line)
        if m:
            arg = m.group(2)
            current = [m.group(1), arg.split("|") if arg and "|" in arg else None, line.strip()]
            options[current[0]] = current
        elif current is not None and line.startswith("    ") and line.strip():
            current[2] += " " + line.strip()
        else:
            current = None
    result = {}
    for flag, values, text in options.values():
        d = HELP_DEFAULT.search(text)
        result[flag] = (values, d.group(1) if d else None)
    return result


def script_option(help_text, flag):
    """(present, default or None) for a flag in a script's prose --help (`--flag ARG (..., default X)`)."""
    if not re.search(r"(?<![\w-])" + re.escape(flag) + r"(?![\w-])", help_text):
        return False, None
    d = re.search(re.escape(flag) + r"(?![\w-])(?:\s+[A-Z_:\[\]]+)?\s*\((?:[^()]*?[,;]\s*)?default\s+([^()\s,;:]+)",
                  help_text)
    return True, d.group(1) if d else None


def check(readme, binary_helps, script_help):
    """Every mismatch between README's flag tables and the --help texts, as messages."""
    errors = []
    rows = readme_flag_rows(readme)
    if not rows:
        errors.append("README.md: no flag table (a table whose first header cell is `flag`)")
    options = {name: binary_options(text) for name, text in binary_helps.items()}
    for n, flag, values, default, says_default, for_script in rows:
        where = f"README.md:{n}: {flag}"
        if not flag.startswith("--"):
            errors.append(f"README.md:{n}: the first cell names no flag in backticks: {flag}")
            continue
        if says_default and default is None:
            errors.append(f"{where}: the row says 'default' but not as default `VALUE`, so it cannot be checked")
        if for_script:
            present, help_default = script_option(script_help, flag)
            if not present:
                errors.append(f"{where}: README marks it (cluster.sh) but scripts/cluster.sh --help does not name it")
            elif default is not None and help_default != default:
                errors.append(f"{where}: README says default `{default}`, scripts/cluster.sh --help says "
                              f"{'default ' + help_default if help_default else 'no default'}")
            continue
        owners = [name for name in options if flag in options[name]]
        if not owners:
            errors.append(f"{where}: not in the --help of {' or '.join(options)}"
                          + (" (a cluster.sh flag? mark the row (cluster.sh))"
                             if script_option(script_help, flag)[0] else ""))
            continue
        for name in owners:
            help_values, help_default = options[name][flag]
            for v in values or []:
                if help_values is not None and v not in help_values:
                    errors.append(f"{where}: README lists the value '{v}', {name} --help offers "
                                  f"{'|'.join(help_values)}")
            if default is not None and help_default != default:
                errors.append(f"{where}: README says default `{default}`, {name} --help says "
                              f"{'default ' + help_default if help_default else 'no default'}")
    return errors


def self_check():
    """The checker finds each kind of mismatch (and no false one) on made-up texts."""
    readme = "\n".join([
        "| flag | what it does |",
        "|---|---|",
        "| `--good a\\|b` | fine (default `a`) |",
        "| `--wrong-default N` | x (default `3`) |",
        "| `--missing` | x |",
        "| `--bad-value a\\|c` | x |",
        "| `--unreadable N` | x (default 4) |",
        "| `--link D` | (cluster.sh) x (default `1`) |",
        "| `--gone` | (cluster.sh) x |",
        "| `--wrapped N` | x (default `7`) |",
        "",
        "| key | action |",
        "|---|---|",
        "| `--not-a-flag-table` | x |",
    ])
    helps = {"prog": "\n".join([
        "options:",
        "  --good a|b                  good (default a)",
        "  --wrong-default N           (default 2)",
        "  --bad-value a|b             (default a)",
        "  --unreadable N              (default 4)",
        "  --wrapped N                 a long text",
        "                              going on (default 7)",
    ])}
    script = "--link D (relay, default 0): a link."
    got = check(readme, helps, script)
    want = [
        "README.md:4: --wrong-default: README says default `3`, prog --help says default 2",
        "README.md:5: --missing: not in the --help of prog",
        "README.md:6: --bad-value: README lists the value 'c', prog --help offers a|b",
        "README.md:7: --unreadable: the row says 'default' but not as default `VALUE`, so it cannot be checked",
        "README.md:8: --link: README says default `1`, scripts/cluster.sh --help says default 0",
        "README.md:9: --gone: README marks it (cluster.sh) but scripts/cluster.sh --help does not name it",
    ]
    if got != want:
        print("self-check failed: the checker's messages on made-up texts were")
        print("\n".join(got))
        print("expected")
        print("\n".join(want))
        return False
    return True


def run_help(cmd):
    out = subprocess.run([*cmd, "--help"], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} --help exited with {out.returncode}: {out.stderr.strip()}")
    return out.stdout + out.stderr


def main():
    if len(sys.argv) != 4:
        raise SystemExit(__doc__)
    if not self_check():
        return 1
    root = pathlib.Path(sys.argv[1])
    helps = {pathlib.Path(p).name: run_help([p]) for p in sys.argv[2:4]}
    script_help = run_help(["bash", str(root / "scripts" / "cluster.sh")])
    errors = check((root / "README.md").read_text(encoding="utf-8"), helps, script_help)
    for e in errors:
        print(e)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
