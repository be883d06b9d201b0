#!/usr/bin/env bash
# End-to-end `tdf batch` with the real tdf on tiny jobs (docs/commands/batch.md):
#   batch_test.sh local TDF SOURCE_DIR WORK_DIR   the local engine, no Slurm needed
#   batch_test.sh slurm TDF SOURCE_DIR WORK_DIR   a throw-away single-node Slurm (tests/batch/slurm_cluster.sh)
# Five jobs: two optimize runs (one long enough to be stopped with SIGTERM, which must checkpoint
# and later continue), a render, a compare, and a render that fails. Checked: exit codes,
# statuses, the error line, attempts, outputs, the summary. Exit 77 = skipped (no Slurm).
# Waiting uses bounded polling loops (this is a test driver, not tdf).
set -euo pipefail
engine=$1
tdf=$2
src=$3
work=$4
rm -rf "$work"
mkdir -p "$work"
cd "$work"

fail() { echo "FAIL: $*" >&2; exit 1; }
# wait_for <seconds> <description> <command...>: polls every 0.2 s, fails after the bound
wait_for() {
  local limit=$1 what=$2; shift 2
  for _ in $(seq 1 $((limit * 5))); do "$@" && return 0; sleep 0.2; done
  fail "timed out after ${limit}s waiting for $what"
}
state() { python3 -c "import json,sys; print(json.load(open('$1'))['$2'])" 2>/dev/null || true; }
if ! command -v python3 >/dev/null; then
  state() { grep -o "\"$2\": *[^,}]*" "$1" 2>/dev/null | head -1 | sed 's/.*: *//; s/"//g'; }
fi

scene=$src/scenes/pebble_sphere/scene.json
golden=$src/reference/golden/pebble_visualizer
small="optimize.resolution=32 optimize.patch_resolution=32 optimize.batch_size=1 optimize.patch_batch_size=1"
small="$small optimize.held_out_views=1 optimize.held_out_patches=1 export.texture_size=64 export.turntable_views=1"
small="$small export.turntable_resolution=32 export.glb=false guidance.tactile=none guidance.visual=none"
cat > manifest.csv <<EOF
name,command,args
opt_small,optimize,$scene optimize.iterations=4 optimize.init_iterations=2 $small --name pebble
opt_long,optimize,$scene optimize.iterations=600 optimize.init_iterations=550 optimize.checkpoint_every=5 $small --name pebble
render_views,render,$scene image.width=32 image.height=32 --png
compare_golden,compare,$golden/view_000.exr $golden/view_000.exr
broken,render,$scene image.width=0
EOF

if [ "$engine" = slurm ]; then
  daemons=$work/slurm-daemons
  set +e
  env_line=$(bash "$src/tests/batch/slurm_cluster.sh" start "$daemons")
  rc=$?
  set -e
  [ $rc = 77 ] && exit 77
  [ $rc = 0 ] || fail "could not start the test Slurm"
  trap 'bash "$src/tests/batch/slurm_cluster.sh" stop "$daemons"' EXIT
  eval "$env_line"
  # --max-array-size 3: two arrays (jobs 0-2, then 3-4 as task ids 0-1). render_views kills itself
  # on its first attempt (test-only TDF_TEST_KILL_JOBS, passed to the tasks by sbatch): failed-resource,
  # so the finish job submits a retry round, which --wait follows.
  TDF_TEST_KILL_JOBS=render_views "$tdf" batch run manifest.csv -o b --engine slurm --cpus-per-task 1 \
    --max-parallel 2 --signal-seconds 60 --max-array-size 3 --wait > run1.out 2> run1.err &
else
  # One job at a time: opt_small, then opt_long, which the SIGTERM below stops; the rest never start.
  "$tdf" --threads 2 batch run manifest.csv -o b --jobs 1 > run1.out 2> run1.err &
fi
runner=$!

# Stop opt_long once it has written its first checkpoint (iteration 5 of 600: its SIGTERM handler
# is installed by then). Polled tightly and without Python: the whole job takes about 6 s on a
# quiet machine, and the signal must find it running.
for _ in $(seq 1 6000); do test -s b/jobs/opt_long/checkpoint.bin && break; sleep 0.05; done
test -s b/jobs/opt_long/checkpoint.bin || fail "timed out after 300s waiting for opt_long's first checkpoint"
if [ "$engine" = slurm ]; then
  # Hold opt_long (SIGSTOP) while the signal travels through Slurm: under load, scancel's signal
  # can arrive seconds later, after the job has ended, and then there is nothing to interrupt. The
  # SIGTERM the runner passes on stays pending until SIGCONT.
  job_pid=$(pgrep -f -- "optimize .* -o .*/b/jobs/opt_long$" | head -1)
  [ -n "$job_pid" ] || fail "opt_long's tdf ended before it could be held (no process)"
  kill -STOP "$job_pid"
fi
opt_long_running() { [ "$(state b/state/opt_long.json status)" = running ]; }
wait_for 30 "opt_long running" opt_long_running
if [ "$engine" = slurm ]; then
  task=$(state b/state/opt_long.json slurm_job)
  [ -n "$task" ] || fail "no Slurm task id in opt_long's state"
  # SIGTERM to the task runner, as before a preemption. The signal is delivered at once, but scancel
  # then keeps retrying for a minute ("Job can not be altered now") while the task requeues
  # itself: bound it; the requeue below is what counts.
  timeout 10 scancel --batch --signal=TERM "$task" 2>/dev/null || true
  passed_on() { grep -q "passing SIGTERM" b/logs/slurm-*_1.out 2>/dev/null; }
  wait_for 60 "the task runner passing SIGTERM to opt_long" passed_on
  kill -CONT "$job_pid"
  # The runner requeues the task; Slurm holds a requeued job ~2 minutes (BeginTime): release it now.
  # (A function, so that squeue is asked again on every poll, not once when wait_for is called.)
  requeued() { [ "$(squeue -h -j "$task" -o %T 2>/dev/null)" = PENDING ]; }
  wait_for 120 "opt_long requeued" requeued
  # Not within a second of the requeue: slurmd refuses a job whose credential is no newer than the
  # revocation of its previous run (which it records a moment after the requeue), compared in whole
  # seconds ("Job credential revoked", and the task fails for good; seen in CI). Slurm's own delay
  # avoids that; a release in the same second does not. So: two clock seconds on.
  requeued_at=$(date +%s)
  two_seconds_on() { [ "$(date +%s)" -gt "$((requeued_at + 1))" ]; }
  wait_for 5 "two clock seconds after the requeue" two_seconds_on
  scontrol update JobId="$task" StartTime=now
  set +e; wait $runner; rc=$?; set -e
  [ $rc = 2 ] || { cat run1.err; fail "tdf batch run --engine slurm --wait: exit $rc, expected 2 (one job failed)"; }
  ls b/logs/slurm-*_1.out > /dev/null || fail "no per-task Slurm log"
  ls b/logs/slurm-summary-*.out > /dev/null || fail "the summary job did not run"
  grep -q "requeued Slurm task" b/logs/slurm-*_1.out || fail "the interrupted task was not requeued"
  test -s b/slurm/array_1.sh || fail "5 jobs with --max-array-size 3 were not split into two arrays"
  grep -q '"$((3 + SLURM_ARRAY_TASK_ID))"' b/slurm/array_1.sh || fail "the second array does not offset its task ids"
  [ "$(grep -c '' b/slurm/submissions.jsonl)" = 2 ] || fail "expected the first submission and one retry round"
  [ "$(state b/state/render_views.json attempts)" = 2 ] || fail "render_views should have been retried once"
  [ "$(state b/state/render_views.json class)" = done ] || fail "render_views is not done after its retry"
  [ "$(state b/state/broken.json attempts)" = 1 ] || fail "the bad input was retried"
else
  kill -TERM $runner   # the batch passes SIGTERM to its running jobs and starts no new one
  set +e; wait $runner; rc=$?; set -e
  [ $rc = 3 ] || { cat run1.err; fail "interrupted batch: exit $rc, expected 3"; }
  [ "$(state b/state/opt_long.json status)" = interrupted ] || fail "opt_long is not 'interrupted'"
  set +e; "$tdf" batch status b > status1.out; rc=$?; set -e
  [ $rc = 3 ] || fail "tdf batch status on an unfinished batch: exit $rc, expected 3"
  grep -q "interrupted by SIGTERM after iteration" b/logs/opt_long.log || fail "opt_long did not say it was interrupted"

  # A changed manifest is refused, saying what changed.
  sed 's/image.width=0/image.width=8/' manifest.csv > changed.csv
  set +e; "$tdf" batch run changed.csv -o b 2> changed.err; rc=$?; set -e
  [ $rc = 1 ] || fail "changed manifest: exit $rc, expected 1"
  grep -q "job 'broken': args differ" changed.err || { cat changed.err; fail "the refusal does not name the change"; }

  # The same manifest again runs only what is not done.
  set +e; "$tdf" --threads 2 batch run manifest.csv -o b > run2.out 2> run2.err; rc=$?; set -e
  [ $rc = 2 ] || { cat run2.err; fail "second run: exit $rc, expected 2 (one job failed)"; }
  grep -q "started opt_small" run2.err && fail "opt_small ran again although it was done"
fi

# Every job's final state.
for job in opt_small opt_long render_views compare_golden; do
  [ "$(state b/state/$job.json status)" = done ] || { cat b/logs/$job.log; fail "$job is not done"; }
done
[ "$(state b/state/broken.json status)" = failed ] || fail "broken is not failed"
grep -q "image size 0x" b/state/broken.json || fail "broken's error line is missing"
[ "$(state b/state/opt_long.json attempts)" = 2 ] || fail "opt_long should have taken 2 attempts"
grep -q "resuming at iteration" b/logs/opt_long.log || fail "opt_long did not resume from its checkpoint"
test -s b/jobs/opt_long/pebble_complete.json || fail "opt_long has no completion record"
test -s b/jobs/opt_small/pebble_albedo.png || fail "opt_small has no albedo map"
test -s b/jobs/render_views/view_000_lambertian.png || fail "render_views has no PNG"
set +e; "$tdf" batch status b > status.out; rc=$?; set -e
[ $rc = 2 ] || fail "tdf batch status: exit $rc, expected 2"
grep -q "5 jobs: 4 done, 1 failed, 0 interrupted, 0 running, 0 pending" status.out || { cat status.out; fail "totals"; }
# The summary: a row per job, the quality numbers, thumbnails.
test -s b/summary.json || fail "no summary.json"
[ "$(wc -l < b/summary.csv)" = 6 ] || fail "summary.csv should have a header and 5 rows"
head -1 b/summary.csv | grep -q "quality.albedo_psnr_foreground_db" || fail "no optimize quality column"
head -1 b/summary.csv | grep -q "quality.psnr" || fail "no compare quality column"
grep -q '"thumbnail": "jobs/opt_small/turntable/lambertian_000.png"' b/summary.json || fail "opt_small thumbnail"
grep -q '"thumbnail": "jobs/render_views/view_000_lambertian.png"' b/summary.json || fail "render thumbnail"
echo "batch test ($engine): OK"
