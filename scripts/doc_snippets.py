#!/usr/bin/env python3
"""The code snippets of README.md and docs/*.md as runnable programs: the docs' examples are
tested, not just read.

Every fenced block tagged ``python`` or ``cpp`` is a snippet. A snippet that is a fragment (it
uses a simulator or a window it does not declare) takes its context from an HTML comment right
above its fence, which Markdown does not render:

    <!-- snippet prelude
    stabint::Simulator sim(stabint::makeClothGrid({}), stabint::SimulatorOptions{});
    -->

The prelude's code runs before the snippet's. A C++ snippet without ``int main`` becomes the body
of one: its ``#include`` lines move to the top (with ``<stabint/stabint.hpp>``), the prelude and
the rest go inside ``main``. A Python snippet runs as a script (``__name__ == "__main__"``).

    doc_snippets.py --cpp OUTDIR    writes OUTDIR/<doc>_<line>.cpp for each C++ snippet and prints
                                    their names (the build compiles and runs each: tests/CMakeLists)
    doc_snippets.py --list          lists every snippet as doc:line language
python/tests/test_doc_snippets.py runs the Python snippets.
"""
import argparse
import pathlib
import re
import sys
from dataclasses import dataclass
from typing import List

ROOT = pathlib.Path(__file__).resolve().parents[1]
LANGUAGES = ("python", "cpp")
PRELUDE = re.compile(r"<!-- snippet prelude\n(.*?)-->\s*$", re.S)


@dataclass
class Snippet:
    doc: str  # the Markdown file, relative to the repository root
    line: int  # the fence's line (1-based)
    language: str
    code: str
    prelude: str

    @property
    def name(self) -> str:
        return re.sub(r"[^A-Za-z0-9]+", "_", f"{self.doc[:-3]}_{self.line}").strip("_")

    def program(self) -> str:
        if self.language == "python":
            return f"# {self.doc}:{self.line}\n{self.prelude}{self.code}"
        if re.search(r"\bint\s+main\s*\(", self.code):
            return f"// {self.doc}:{self.line}\n{self.prelude}{self.code}"
        lines = (self.prelude + self.code).splitlines()
        includes = [line for line in lines if line.startswith("#include")]
        body = [line for line in lines if not line.startswith("#include")]
        head = ["#include <stabint/stabint.hpp>"] + [i for i in includes if i != "#include <stabint/stabint.hpp>"]
        return "\n".join([f"// {self.doc}:{self.line}", *head, "", "int main() {", *("  " + b for b in body),
                          "  return 0;", "}", ""])


def documents() -> List[pathlib.Path]:
    return [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))


def snippets(language: str = "") -> List[Snippet]:
    found = []
    for path in documents():
        lines = path.read_text().splitlines(keepends=True)
        i = 0
        while i < len(lines):
            fence = re.match(r"^```(\w+)\s*$", lines[i])
            if not fence:
                i += 1
                continue
            start, tag = i, fence.group(1)
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                i += 1
            if tag in LANGUAGES and (not language or tag == language):
                before = "".join(lines[max(0, start - 40):start])
                prelude = PRELUDE.search(before)
                found.append(Snippet(str(path.relative_to(ROOT)), start + 1, tag, "".join(lines[start + 1:i]),
                                     prelude.group(1) if prelude else ""))
            i += 1
    return found


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cpp", metavar="OUTDIR", help="write the C++ snippets as programs into OUTDIR")
    parser.add_argument("--list", action="store_true", help="list the snippets")
    args = parser.parse_args()
    if args.list:
        for s in snippets():
            print(f"{s.doc}:{s.line} {s.language}{' (prelude)' if s.prelude else ''}")
    if args.cpp:
        out = pathlib.Path(args.cpp)
        out.mkdir(parents=True, exist_ok=True)
        names = []
        for s in snippets("cpp"):
            target = out / f"{s.name}.cpp"
            text = s.program()
            if not target.exists() or target.read_text() != text:  # unchanged files keep their timestamps
                target.write_text(text)
            names.append(s.name)
        print(";".join(names), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
