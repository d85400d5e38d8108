#!/usr/bin/env bash
# All linters; exits non-zero if any complains. `make test` runs the same checks as tests (tests/test_lint.py).
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
exec .venv/bin/pytest -q -p no:cacheprovider tests/test_lint.py
