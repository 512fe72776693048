# Sourced by the end-to-end scripts here (after their arguments are read): a temporary
# folder `dir`, removed on exit, and the two ways they report a failure.
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
failures=0
fail() { echo "FAIL: $*"; exit 1; }  # the first failure ends the script
# Counts and goes on; such a script ends with `exit $((failures > 0))`.
fail_and_go_on() { echo "FAIL: $*"; failures=$((failures + 1)); }
