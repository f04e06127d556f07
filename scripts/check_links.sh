#!/usr/bin/env bash
# Checks the relative links of the repository's Markdown files (every tracked *.md, or the files
# given): each [text](target) and ![alt](target) that is not a URL must name a file or folder that
# exists, relative to the linking file, and a #fragment must be a heading of the target (GitHub's
# anchors: lower case, punctuation dropped, spaces as hyphens, -1, -2, ... for repeats). Fails,
# naming the file and line, on a link that does not resolve.
#   bash scripts/check_links.sh [FILE.md...]
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -eq 0 ]; then
  mapfile -t files < <(git ls-files '*.md' | while read -r f; do [ -f "$f" ] && echo "$f"; done)
else
  files=("$@")
fi
/usr/bin/env python3 - "${files[@]}" <<'PY'
import os, re, sys

LINK = re.compile(r'!?\[(?:[^\]\\]|\\.)*\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\)')
HEADING = re.compile(r'^(#{1,6})\s+(.*?)\s*#*\s*$')
FENCE = re.compile(r'^\s*(```|~~~)')


def slug(text):
    text = re.sub(r'<[^>]+>', '', text)            # inline HTML
    text = re.sub(r'\[([^\]]*)\]\([^)]*\)', r'\1', text)  # links: their text
    text = text.replace('`', '').strip().lower()
    text = re.sub(r'[^\w\- ]', '', text)            # punctuation (keeps letters, digits, _ and -)
    return text.replace(' ', '-')


def lines_outside_fences(path):
    inside = False
    with open(path, encoding='utf-8') as f:
        for number, line in enumerate(f, 1):
            if FENCE.match(line):
                inside = not inside
                continue
            if not inside:
                yield number, line


anchors_cache = {}


def anchors(path):
    if path not in anchors_cache:
        seen, found = {}, set()
        for _, line in lines_outside_fences(path):
            m = HEADING.match(line)
            if not m:
                continue
            base = slug(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f'{base}-{n}')
        for _, line in lines_outside_fences(path):     # explicit anchors: <a name="..."> / id="..."
            for m in re.finditer(r'<a\s+(?:name|id)="([^"]+)"', line):
                found.add(m.group(1))
        anchors_cache[path] = found
    return anchors_cache[path]


bad = 0
for source in sys.argv[1:]:
    for number, line in lines_outside_fences(source):
        for m in LINK.finditer(re.sub(r'`[^`]*`', '', line)):
            target = m.group(1)
            if re.match(r'^[a-zA-Z][a-zA-Z0-9+.-]*:', target):  # http:, https:, mailto:, ...
                continue
            path, _, fragment = target.partition('#')
            resolved = os.path.normpath(os.path.join(os.path.dirname(source), path)) if path else source
            if not os.path.exists(resolved):
                print(f'{source}:{number}: {target}: no such file', file=sys.stderr)
                bad += 1
            elif fragment and resolved.endswith('.md') and fragment not in anchors(resolved):
                print(f'{source}:{number}: {target}: no heading with that anchor in {resolved}', file=sys.stderr)
                bad += 1
if bad:
    print(f'check_links: {bad} broken relative link(s)', file=sys.stderr)
    sys.exit(1)
print(f'check_links: ok ({len(sys.argv) - 1} Markdown files)')
PY
