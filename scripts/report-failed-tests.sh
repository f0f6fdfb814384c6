#!/usr/bin/env bash
# Prints, for every build directory given, the tests its last CTest run failed and the end of
# each one's output. CI calls it last, so that a failure is named where the log ends (a log is
# often read from its tail) and not only somewhere in the middle of thousands of lines.
# Usage: scripts/report-failed-tests.sh [--since EPOCH_SECONDS] BUILD_DIR...
set -uo pipefail
since=0
if [ "${1:-}" = "--since" ]; then since="${2:?--since needs seconds since the epoch}"; shift 2; fi
lines_per_test="${FLEXIROB_FAILED_TEST_LINES:-40}"
for dir in "$@"; do
  failed="$dir/Testing/Temporary/LastTestsFailed.log"
  log="$dir/Testing/Temporary/LastTest.log"
  [ -s "$failed" ] || continue
  [ "$(stat -c %Y "$failed")" -ge "$since" ] || continue  # left from an earlier run
  echo "=== failed tests in $dir:"
  sed 's/^[0-9]*:/    /' "$failed"
  [ -f "$log" ] || continue
  while IFS=: read -r _ name; do
    echo "--- end of the output of $name:"
    # A test's section runs from its "N/M Testing: name" line to its "Test Passed/Failed" line.
    # The lines that say what failed (GoogleTest, QtTest, sanitizers), then the output's end.
    # The name through the environment: awk -v would read backslashes in it as escapes.
    TEST_NAME="$name" awk -v limit="$lines_per_test" '
      $0 ~ "^[0-9]+/[0-9]+ Testing: " && substr($0, index($0, ": ") + 2) == ENVIRON["TEST_NAME"] { inside = 1; n = 0; m = 0; next }
      inside && /^Test (Passed|Failed|Not Run)|^Test time/ { inside = 0 }
      inside { kept[n++] = $0; if ($0 ~ /FAIL!|Loc: \[|: Failure$|^\[  FAILED  \]|ERROR: .*Sanitizer|WARNING: ThreadSanitizer|runtime error:/ && m < 20) marks[m++] = $0 }
      END {
        for (i = 0; i < m; i++) print "  ! " marks[i]
        for (i = n > limit ? n - limit : 0; i < n; i++) print "    " kept[i]
      }
    ' "$log"
  done < "$failed"
done
