#!/usr/bin/env bash
# The API reference: Doxygen over the public headers (include/stabint/, docs/Doxyfile) into
# build/apidocs/html/index.html, and the Python reference (pydoc, scripts/apidocs_python.py) into
# build/apidocs/python/index.html. Installs doxygen if missing (scripts/install-deps.sh). Fails on
# any warning, an undocumented public declaration included (WARN_AS_ERROR = FAIL_ON_WARNINGS), so
# CI keeps the headers' comments complete.
set -euo pipefail
cd "$(dirname "$0")/.."

command -v doxygen >/dev/null || bash scripts/install-deps.sh
mkdir -p build/apidocs
# The options' members come from an X-macro: their docs are generated from the same rows.
python3 scripts/apidocs_options.py build/apidocs/generated/options.dox
log=build/apidocs/warnings.log
# Doxygen writes its warnings to stderr; keep them in a log and print them.
if ! doxygen docs/Doxyfile 2> "$log" || [ -s "$log" ]; then
  cat "$log" >&2
  echo "apidocs: $(grep -c . "$log") warning(s); see $log" >&2
  exit 1
fi
echo "apidocs: 0 warnings; build/apidocs/html/index.html"
# The Python reference, from the installed package's docstrings (scripts/python.sh installs it
# into .venv); a public name without a docstring fails, as an undocumented declaration does above.
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import stabint" 2>/dev/null; then
  echo "apidocs: the Python reference needs the package in .venv: run bash scripts/python.sh first" >&2
  exit 1
fi
.venv/bin/python scripts/apidocs_python.py build/apidocs/python
