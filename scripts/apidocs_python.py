#!/usr/bin/env python3
"""The Python API reference: pydoc's HTML of every module of the installed package (the
extension's docstrings, the stubs' signatures through them, and the pure-Python modules) into
OUTDIR/<module>.html with an index, and a check that fails on any public name without a docstring
(the Python side of Doxygen's undocumented-declaration warning). scripts/apidocs.sh runs it with
.venv's interpreter.   usage: apidocs_python.py OUTDIR"""
import importlib
import inspect
import pathlib
import pydoc
import sys

MODULES = ["stabint", "stabint._stabint", "stabint.distributed", "stabint.io"]


def undocumented(module):
    """Public names of `module` (its __all__, else every name not starting with _) without a
    docstring of their own, and the public methods and properties of its classes likewise."""
    names = getattr(module, "__all__", None) or [n for n in dir(module) if not n.startswith("_")]
    missing = []
    for name in names:
        obj = getattr(module, name)
        if inspect.ismodule(obj) or not (callable(obj) or inspect.isclass(obj)):
            continue  # constants and submodules document themselves where they are defined
        if not (getattr(obj, "__doc__", None) or "").strip():
            missing.append(f"{module.__name__}.{name}")
        if inspect.isclass(obj):
            for attr, member in vars(obj).items():
                if attr.startswith("_") or not (callable(member) or isinstance(member, property) or
                                                type(member).__name__ in ("nb_property", "getset_descriptor")):
                    continue
                if isinstance(member, (staticmethod, classmethod)):
                    member = member.__func__
                if not (getattr(member, "__doc__", None) or "").strip():
                    missing.append(f"{module.__name__}.{name}.{attr}")
    return missing


def main() -> int:
    out = pathlib.Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    missing, links = [], []
    for name in MODULES:
        module = importlib.import_module(name)
        missing += undocumented(module)
        page = pydoc.html.page(pydoc.describe(module), pydoc.html.document(module, name))
        (out / f"{name}.html").write_text(page)
        summary = (inspect.getdoc(module) or "").split("\n")[0]
        links.append(f'<li><a href="{name}.html">{name}</a>: {summary}</li>')
    (out / "index.html").write_text("<html><head><title>stabint Python reference</title></head><body>"
                                    "<h1>stabint: the Python reference</h1><ul>" + "".join(links) +
                                    "</ul></body></html>\n")
    if missing:
        print(f"apidocs_python: {len(missing)} public name(s) without a docstring:", file=sys.stderr)
        for m in missing:
            print(f"  {m}", file=sys.stderr)
        return 1
    print(f"apidocs_python: {len(MODULES)} modules, every public name documented; {out}/index.html")
    return 0


if __name__ == "__main__":
    sys.exit(main())
