#!/usr/bin/env bash
# Style checks: ruff lint over all Python, ruff format over the files already formatted (the
# "not formatted yet" list in ruff.toml's [format] exclude shrinks as files are touched), and
# clang-format over the C++ files listed in .clang-format-checked. A tool that is missing skips
# its check with a message (scripts/setup.sh installs ruff with pip and clang-format with apt).
set -uo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
status=0
RUFF=$(command -v ruff || { [ -x .venv/bin/ruff ] && echo .venv/bin/ruff; } || true)
if [ -n "$RUFF" ]; then
  "$RUFF" check addon python_tests scripts blend_fixtures || status=1
  "$RUFF" format --check addon python_tests scripts blend_fixtures || status=1
else
  echo "skipped: ruff is not installed (pip install ruff)"
fi
if command -v clang-format >/dev/null; then
  grep -v '^#' .clang-format-checked | xargs clang-format --dry-run --Werror || status=1
else
  echo "skipped: clang-format is not installed (apt-get install clang-format)"
fi
exit $status
