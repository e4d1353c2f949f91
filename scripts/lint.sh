#!/usr/bin/env bash
# lint.sh: format and static checks; exits 1 on any finding.
#   scripts/lint.sh            both checks
#   scripts/lint.sh format     (a) clang-format --dry-run --Werror over every tracked .c/.h file (.clang-format)
#   scripts/lint.sh tidy       (b) clang-tidy (.clang-tidy) over every firmware/ source in the host build's
#                              compile_commands.json (scripts/build.sh makes it); any warning fails
# The Cortex-M board files and images (firmware/port/cortex-m, firmware/apps/cortex-m) are compiled only by the
# cross build and are not in the host database, so clang-tidy does not see them.
# Environment: LSM_BUILD_DIR (default <repo>/build), LSM_LINT_JOBS (default nproc).
# Fix format drift with: git ls-files '*.c' '*.h' | xargs clang-format -i
set -uo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
BUILD=${LSM_BUILD_DIR:-$ROOT/build}
JOBS=${LSM_LINT_JOBS:-$(nproc)}
what=${1:-all}
rc=0

for tool in clang-format clang-tidy; do
    command -v "$tool" >/dev/null || { echo "lint: $tool not found (scripts/deps.sh installs it)"; exit 2; }
done

if [ "$what" = all ] || [ "$what" = format ]; then
    mapfile -t files < <(git ls-files '*.c' '*.h')
    out=$(printf '%s\0' "${files[@]}" | xargs -0 -n 16 -P "$JOBS" clang-format --dry-run --Werror 2>&1)
    if [ -n "$out" ]; then
        bad=$(printf '%s\n' "$out" | grep -oE '^[^:]+\.(c|h):[0-9]+' | cut -d: -f1 | sort -u)
        printf '%s\n' "$out" | head -40
        echo "lint: format drift in $(printf '%s\n' "$bad" | wc -l) of ${#files[@]} files: $(echo $bad)"
        rc=1
    else
        echo "lint: format ok (${#files[@]} files)"
    fi
fi

if [ "$what" = all ] || [ "$what" = tidy ]; then
    db=$BUILD/compile_commands.json
    [ -f "$db" ] || { echo "lint: no $db (run scripts/build.sh first)"; exit 2; }
    mapfile -t srcs < <(python3 - "$db" "$ROOT" <<'EOF'
import json, sys
db, root = sys.argv[1], sys.argv[2]
files = sorted({e["file"] for e in json.load(open(db)) if e["file"].startswith(root + "/firmware/")})
print("\n".join(files))
EOF
)
    log=$(mktemp)
    printf '%s\0' "${srcs[@]}" | xargs -0 -n 1 -P "$JOBS" clang-tidy -p "$BUILD" --quiet >"$log" 2>&1
    tidy_rc=$?
    findings=$(grep -E '^[^ ]+:[0-9]+:[0-9]+: (warning|error):' "$log" | sort -u)
    if [ -n "$findings" ]; then
        printf '%s\n' "$findings"
        echo "lint: clang-tidy: $(printf '%s\n' "$findings" | wc -l) findings in ${#srcs[@]} firmware sources"
        rc=1
    elif [ $tidy_rc -ne 0 ]; then
        cat "$log"
        echo "lint: clang-tidy failed to run"
        rc=1
    else
        echo "lint: clang-tidy ok (${#srcs[@]} firmware sources)"
    fi
    rm -f "$log"
fi

[ $rc -eq 0 ] && echo "lint: PASS" || echo "lint: FAIL"
exit $rc
