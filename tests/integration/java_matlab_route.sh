#!/usr/bin/env bash
# MATLAB's route, in Java: MATLAB's bundled Java is 8, so spindown_types.jar must be Java 8 class
# files (major 52). A small Java program compiled with javac --release 8 against lcm.jar and the
# types jar checks every class file's major version in both jars (javac itself accepts newer class
# files on the class path, so that check is the guard), opens a real spindown-logger log with
# lcm.logging.Log as MATLAB does, decodes every SPINDOWN.* channel with the types jar, and
# compares the samples with `spindown export --csv`.
source "$(dirname "$0")/lab_log_common.bash"
for tool in java javac; do
  command -v "$tool" >/dev/null 2>&1 || fail "$tool not installed (deploy/setup: default-jdk-headless)"
done
TYPES_JAR=${SPINDOWN_TYPES_JAR:-}
LCM_JAR=${SPINDOWN_LCM_JAR:-/usr/share/java/lcm.jar}
[[ -n $TYPES_JAR && -f $TYPES_JAR ]] || fail "no types jar (SPINDOWN_TYPES_JAR='$TYPES_JAR'): build spindown_types_jar"
[[ -f $LCM_JAR ]] || fail "no $LCM_JAR (deploy/setup: liblcm-java)"

mkdir "$WORK/classes"
javac --release 8 -Xlint:-options -d "$WORK/classes" -cp "$LCM_JAR:$TYPES_JAR" "$SRC/tests/java/SpindownLogCheck.java" \
  >"$WORK/javac.out" 2>&1 || fail "javac --release 8 failed: $(cat "$WORK/javac.out")"

make_lab_log "$WORK/lab"
rc=0
java -cp "$LCM_JAR:$TYPES_JAR:$WORK/classes" SpindownLogCheck "$TYPES_JAR" "$LCM_JAR" "$LAB_LOG" "$LAB_CSV" \
  >"$WORK/check.out" 2>&1 || rc=$?
cat "$WORK/check.out"
(( rc == 0 )) || fail "the Java 8 reader (exit $rc) disagrees"
grep -q '^PASS' "$WORK/check.out" || fail "no PASS line"
echo "PASS: a Java 8 program reads the log with lcm.logging.Log and the Java 8 types jar, as MATLAB does"
