#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Checks the relative links of the project's Markdown files: every linked file exists and every
`#anchor` names a heading of the linked file (GitHub's rule: lower case, punctuation dropped,
spaces to hyphens, repeated headings numbered -1, -2, ...). Links to web addresses are not
followed. Prints each broken link as FILE:LINE and exits 1 if there is one.

    tests/docs/check_links.py [REPOSITORY_ROOT]
"""
import os
import re
import sys
import unicodedata

FOLDERS = ("docs", "examples", "experiments", "python", "tests")
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")


def markdown_files(root):
    files = [os.path.join(root, "README.md")]
    for folder in FOLDERS:
        for directory, subdirectories, names in os.walk(os.path.join(root, folder)):
            subdirectories[:] = [d for d in subdirectories if not d.startswith(".")]
            files += [os.path.join(directory, n) for n in names if n.endswith(".md")]
    return [f for f in files if os.path.isfile(f)]


def outside_code(path):
    """(line number, line) of the lines outside fenced code blocks."""
    fenced = False
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if line.lstrip().startswith("```"):
                fenced = not fenced
                continue
            if not fenced:
                yield number, line


def slug(heading):
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading.replace("`", "").strip().lower())
    kept = "".join(c for c in text if c in " -_" or unicodedata.category(c)[0] in "LN")
    return kept.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        found, counts = set(), {}
        for _, line in outside_code(path):
            match = HEADING.match(line)
            if match:
                base = slug(match.group(2))
                count = counts.get(base, 0)
                counts[base] = count + 1
                found.add(base if count == 0 else f"{base}-{count}")
        cache[path] = found
    return cache[path]


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), "..", ".."))
    files, broken = markdown_files(root), 0
    for path in sorted(files):
        for number, line in outside_code(path):
            for match in LINK.finditer(re.sub(r"`[^`]*`", "", line)):  # not inside inline code
                target = match.group(1)
                if re.match(r"[a-z][a-z0-9+.-]*:", target):
                    continue  # http:, https:, mailto:
                file_part, _, anchor = target.partition("#")
                linked = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) \
                    if file_part else path
                where = f"{os.path.relpath(path, root)}:{number}"
                if not os.path.exists(linked):
                    print(f"{where}: {target}: no such file")
                    broken += 1
                elif anchor and linked.endswith(".md") and anchor not in anchors(linked):
                    print(f"{where}: {target}: no heading with this anchor")
                    broken += 1
    print(f"{len(files)} Markdown files, {broken} broken links")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
