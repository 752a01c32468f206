#!/usr/bin/env bash
# Install anchorplan with its test tools in a fresh virtual environment, lint, run the tests.
# The package is installed non-editable and pytest runs from tests/, so the tests import the
# installed copy, not the source tree (tests/test_packaging.py checks both).
set -euo pipefail
cd "$(dirname "$0")/.."
rm -rf build
python3 -m venv --clear .venv                                        # 1. a new environment
.venv/bin/pip install ".[test]"                                      # 2. the package and its test tools
.venv/bin/ruff check . && .venv/bin/ruff format --check .            # 3. lint and format
cd tests
../.venv/bin/python -m pytest -p no:cacheprovider -m "not slow"      # 4. the tests
../.venv/bin/python -m pytest -p no:cacheprovider -m slow            # 5. the slow ones (whole plans)
