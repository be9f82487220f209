#!/usr/bin/env bash
# Runs the commands of a documentation page as a reader would: every block fenced ```sh, in
# order, as one bash script (set -euo pipefail) in a fresh empty folder whose `build` links to
# the build folder, so `build/tools/msii ...` works as written from the repository. The page
# must have at least one such block; the run fails on the first command that fails.
# Blocks fenced otherwise (```bash: set-up, a user's own files) are not run.
# Usage: test_doc_commands.sh BUILD_DIR PAGE.md
set -euo pipefail
build="$1" page="$2"
fail() { echo "FAIL: $page: $*" >&2; exit 1; }
[ -f "$page" ] || fail "no such page"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
awk '/^```sh[[:space:]]*$/ { inside = 1; blocks++; printf "\n# --- block %d (line %d)\n", blocks, NR; next }
     /^```/ && inside { inside = 0; next }
     inside { print }
     END { if (blocks == 0) exit 3 }' "$page" > "$work/commands.sh" || fail "has no \`\`\`sh block"
ln -s "$(cd "$build" && pwd)" "$work/build"
cd "$work"
echo "running the sh blocks of $page in $work"
if ! bash -euo pipefail -x commands.sh > log.txt 2>&1; then
  tail -n 40 log.txt >&2
  fail "a command failed (the last lines of its output above)"
fi
echo "ok: $(grep -c '^# --- block' commands.sh) blocks"
