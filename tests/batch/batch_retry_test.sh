#!/usr/bin/env bash
# `tdf batch run` with the real tdf on 20 tiny jobs with injected faults (docs/commands/batch.md):
#   batch_retry_test.sh TDF SOURCE_DIR WORK_DIR
# - 2 bad inputs (a mesh that does not parse, a scene that is not JSON): failed-input, one try;
# - 2 jobs SIGKILL themselves on their first attempt (the test-only TDF_TEST_KILL_JOBS, see
#   src/app/main.cpp): failed-resource, retried, done on the second attempt;
# - 1 job SIGKILLs itself on every attempt: failed-resource after 1 + --max-retries (2) tries;
# - the 15 others are done on their first attempt.
# Then: a second run starts nothing (failed for good stays failed), --retry-failed runs the failed
# ones again, --max-failures stops starting jobs, --timeout stops a job that would run for
# minutes, and bad manifests are refused before anything is written. No sleeps: every fault is
# injected, and the timeout's job never ends by itself.
set -euo pipefail
tdf=$1
src=$2
work=$3
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)
cd "$work"

fail() { echo "FAIL: $*" >&2; exit 1; }
field() { python3 -c "import json,sys; print(json.load(open('$1'))['$2'])"; }
expect() {  # expect <job> <key> <value>
  local got
  got=$(field "b/state/$1.json" "$2")
  [ "$got" = "$3" ] || { cat "b/logs/$1.log" >&2 || true; fail "$1: $2 is '$got', expected '$3'"; }
}

scene=$src/scenes/pebble_sphere/scene.json
render="image.width=16 image.height=16"
small="optimize.iterations=4 optimize.init_iterations=2 optimize.resolution=32 optimize.patch_resolution=32"
small="$small optimize.batch_size=1 optimize.patch_batch_size=1 optimize.held_out_views=1"
small="$small optimize.held_out_patches=1 export.texture_size=64 export.turntable_views=1"
small="$small export.turntable_resolution=32 export.glb=false guidance.tactile=none guidance.visual=none"
small="$small field.table_log2=12"
printf 'v 0 0 0\nv 1 0\nf 1 2 3\n' > bad.obj    # a vertex with two coordinates
printf '{"mesh": "sphere.obj", ' > bad_scene.json  # not JSON

{
  echo "name,command,args"
  for k in $(seq -w 0 17); do echo "g$k,render,$scene $render seed=$((10#$k))"; done
  echo "opt0,optimize,$scene $small --name pebble"
  echo "opt1,optimize,$scene $small seed=1 --name pebble"
} > manifest.csv
# Two of the renders become bad inputs (10 %), in place, so the manifest stays 20 rows.
sed -i "s|^g05,render,.*|g05,render,$scene $render mesh=$work/bad.obj|; s|^g12,render,.*|g12,render,$work/bad_scene.json|" manifest.csv
[ "$(grep -c '' manifest.csv)" = 21 ] || fail "the manifest should have 20 rows"
good="g00 g01 g02 g03 g04 g06 g07 g08 g10 g11 g13 g14 g15 g16 g17 opt0 opt1"
killed_once="g03 opt1"

set +e
TDF_TEST_KILL_JOBS="g03,opt1,g09:99" "$tdf" --threads 2 batch run manifest.csv -o b --jobs 2 \
  > run1.out 2> run1.err
rc=$?
set -e
[ $rc = 2 ] || { cat run1.err; fail "run 1: exit $rc, expected 2 (jobs failed)"; }

# Every good job done exactly once: state done, one "done" line, as many attempts as starts.
for job in $good; do
  expect "$job" status done
  expect "$job" class done
  [ "$(grep -c "^done $job in" run1.err)" = 1 ] || fail "$job was not done exactly once"
  attempts=1
  [[ " $killed_once " == *" $job "* ]] && attempts=2
  expect "$job" attempts $attempts
  [ "$(grep -c "^=== tdf batch: job $job, attempt" "b/logs/$job.log")" = $attempts ] ||
    fail "$job's log should hold $attempts attempt(s)"
done
test -s b/jobs/opt1/pebble_complete.json || fail "opt1 has no completion record"
grep -q "failed g03 (failed-resource, try 1 of 3): killed by SIGKILL" run1.err ||
  fail "the first kill of g03 was not reported as a failed-resource try"

# Bad inputs: failed-input, never retried, with the error line.
for job in g05 g12; do
  expect "$job" status failed
  expect "$job" class failed-input
  expect "$job" attempts 1
  expect "$job" exit_code 1
done
field b/state/g05.json error | grep -q "^tdf render: .*bad.obj" || fail "g05's error line does not name the mesh"
field b/state/g12.json error | grep -q "^tdf render: .*bad_scene.json" || fail "g12's error line does not name the scene"

# Killed every time: failed-resource after 3 tries.
expect g09 class failed-resource
expect g09 tries 3
expect g09 error "killed by SIGKILL"

# status: the table and the totals by class, exit 2.
set +e; "$tdf" batch status b > status1.out; rc=$?; set -e
[ $rc = 2 ] || fail "tdf batch status: exit $rc, expected 2"
grep -q "^20 jobs: 17 done, 3 failed, 0 interrupted, 0 running, 0 pending (2 failed-input, 1 failed-resource)$" \
  status1.out || { cat status1.out; fail "status totals"; }
grep -Eq "^g05 +failed +failed-input +[0-9.]+ +1 +1  tdf render: " status1.out || { cat status1.out; fail "g05's status row"; }
grep -Eq "^g09 +failed +failed-resource +[0-9.]+ +3 +3  killed by SIGKILL$" status1.out || { cat status1.out; fail "g09's status row"; }
grep -Eq "^g03 +done +done +[0-9.]+ +2 +2  jobs/g03$" status1.out || { cat status1.out; fail "g03's status row"; }
python3 - <<'EOF' || fail "summary.json"
import json
s = json.load(open("b/summary.json"))
t = s["totals"]
assert (t["done"], t["failed"], t["failed_input"], t["failed_resource"]) == (17, 3, 2, 1), t
classes = {j["job"]: j["class"] for j in s["jobs"]}
assert classes["g05"] == "failed-input" and classes["g09"] == "failed-resource", classes
EOF
head -1 b/summary.csv | grep -q "^job,command,status,class," || fail "summary.csv has no class column"

# A second run starts nothing: the failed jobs failed for good.
set +e; "$tdf" batch run manifest.csv -o b > run2.out 2> run2.err; rc=$?; set -e
[ $rc = 2 ] || fail "run 2: exit $rc, expected 2"
grep -q "^started " run2.err && { cat run2.err; fail "run 2 started a job"; }
grep -q "nothing to run (17 done, 0 running, 3 failed for good; --retry-failed runs those again)" run2.err ||
  { cat run2.err; fail "run 2 does not say why nothing runs"; }

# --retry-failed: the three run again (no kills now); g09 is done, the bad inputs fail again.
set +e; "$tdf" --threads 2 batch run manifest.csv -o b --retry-failed > run3.out 2> run3.err; rc=$?; set -e
[ $rc = 2 ] || { cat run3.err; fail "run 3: exit $rc, expected 2"; }
[ "$(grep -c "^started " run3.err)" = 3 ] || { cat run3.err; fail "run 3 should start exactly the 3 failed jobs"; }
expect g09 status done
expect g09 attempts 4
expect g05 attempts 2
expect g05 class failed-input

# --max-failures 1: after the first bad input no job starts; they stay pending for the next run.
printf 'name,command,args\nbad,render,%s\nr1,render,%s %s\nr2,render,%s %s\n' \
  "$work/bad_scene.json" "$scene" "$render" "$scene" "$render" > capped.csv
set +e; "$tdf" batch run capped.csv -o c --jobs 1 --max-failures 1 > cap1.out 2> cap1.err; rc=$?; set -e
[ $rc = 2 ] || { cat cap1.err; fail "capped run: exit $rc, expected 2"; }
grep -q "^3 jobs: 0 done, 1 failed, 0 interrupted, 0 running, 2 pending" cap1.out || { cat cap1.out; fail "capped totals"; }
grep -q -- "--max-failures reached: 2 job(s) not started" cap1.err || { cat cap1.err; fail "the cap is not reported"; }
set +e; "$tdf" batch run capped.csv -o c --jobs 1 --max-failures 1 > cap2.out 2> cap2.err; rc=$?; set -e
grep -q "^3 jobs: 2 done, 1 failed" cap2.out || { cat cap2.out cap2.err; fail "the next run did not continue the pending jobs"; }
[ "$(field c/state/bad.json attempts)" = 1 ] || fail "the bad input ran again"

# --timeout: a job of 100000 iterations is stopped at 1 s (it checkpoints on SIGTERM) and ends
# failed-resource; with --max-retries 0 it is not tried again.
printf 'name,command,args\nslow,optimize,%s %s optimize.iterations=100000 --name pebble\n' "$scene" "$small" > slow.csv
set +e; "$tdf" --threads 1 batch run slow.csv -o d --timeout 1 --max-retries 0 > slow.out 2> slow.err; rc=$?; set -e
[ $rc = 2 ] || { cat slow.err; fail "timeout run: exit $rc, expected 2"; }
[ "$(field d/state/slow.json class)" = failed-resource ] || fail "the timed-out job is not failed-resource"
field d/state/slow.json error | grep -q "^timed out after 1 s (--timeout)" || fail "the timeout's error line"

# Bad manifests: one line naming the row, exit 1, no batch folder.
printf 'name,command,args\na,render,%s\nb,render,%s/no_such_scene.json\n' "$scene" "$work" > missing.csv
printf 'name,command,args\na,render,%s\na,render,%s\n' "$scene" "$scene" > duplicate.csv
printf 'name,command,args\na,render,%s image..width=3\n' "$scene" > override.csv
for m in missing duplicate override; do
  set +e; "$tdf" batch run $m.csv -o bad_$m > /dev/null 2> $m.err; rc=$?; set -e
  [ $rc = 1 ] || fail "$m.csv: exit $rc, expected 1"
  [ "$(grep -c '' $m.err)" = 1 ] || { cat $m.err; fail "$m.csv: not one line"; }
  [ ! -e bad_$m ] || fail "$m.csv: the batch folder was created"
done
grep -q "^tdf batch: missing.csv:3: job 'b': input file '.*no_such_scene.json' does not exist$" missing.err || fail "$(cat missing.err)"
grep -q "^tdf batch: duplicate.csv:3: job name 'a' appears twice (first at duplicate.csv:2)$" duplicate.err || fail "$(cat duplicate.err)"
grep -q "^tdf batch: override.csv:2: job 'a': override 'image..width=3' has an empty key component$" override.err || fail "$(cat override.err)"
echo "batch retry test: OK"
