#!/usr/bin/env bash
# Mutation testing (issue 11, item 9): each mutant of bench/mutants.txt alone is applied to a copy
# of HEAD, built, and its module's tests run; prints who killed it and the score (target >= 90%).
# Usage: bash bench/mutate.sh [--dry-run] [--only NAME,...]   (about 1-2 minutes per mutant)
set -euo pipefail
cd "$(dirname "$0")/.."
exec python3 -B bench/mutate.py "$@"
