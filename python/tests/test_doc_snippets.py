"""The Python snippets of README.md and docs/*.md run as scripts (scripts/doc_snippets.py; the
C++ ones are built and run by ctest as DocSnippet.*): an example that stops working fails here.
Each runs in a fresh folder (snippets write files) with this interpreter, as a user pastes it."""

import importlib.util
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("doc_snippets", ROOT / "scripts" / "doc_snippets.py")
doc_snippets = importlib.util.module_from_spec(spec)
spec.loader.exec_module(doc_snippets)
SNIPPETS = doc_snippets.snippets("python")


def test_the_docs_have_python_snippets():
    assert len(SNIPPETS) >= 4  # README's quick start, the guide's, the sweeps' and the I/O's


@pytest.mark.parametrize("snippet", SNIPPETS, ids=[s.name for s in SNIPPETS])
def test_snippet_runs_as_a_script(snippet, tmp_path):
    script = tmp_path / "snippet.py"
    script.write_text(snippet.program())
    result = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, f"{snippet.doc}:{snippet.line} failed:\n{result.stdout}\n{result.stderr}"
