#!/usr/bin/env bash
# Build the HTML documentation with warnings as errors; installs nothing.
# Output: docs/_build/html/index.html. The gallery executes every script of examples/.
set -euo pipefail
cd "$(dirname "$0")/.."
python -m sphinx -W --keep-going -b html docs docs/_build/html "$@"
