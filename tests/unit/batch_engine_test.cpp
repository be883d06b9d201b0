// The batch folder, the local engine (with a stand-in for the tdf executable, so that these
// tests stay fast), the summary and the Slurm array script. The real tdf under the local engine
// and under a real Slurm is tested by tests/batch/batch_test.sh (ctest BatchCli.*).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <tdf/batch/batch_folder.h>
#include <tdf/batch/batch_summary.h>
#include <tdf/batch/job_runner.h>
#include <tdf/batch/slurm_engine.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>

#include "common/test_paths.h"

using namespace tdf;
namespace fs = std::filesystem;

namespace {

std::string fresh(const std::string& name) {
    const std::string path = test::scratch_dir() + "/batch_engine/" + name;
    fs::remove_all(path);
    fs::create_directories(path);
    return path;
}

// A stand-in for tdf: `fake --threads N <command> <args...>`. "ok" succeeds, "fail" prints a tdf
// error line and exits 1, "compare" prints a report; every job writes its thread count.
// "kill N x out" SIGKILLs itself on attempts 1..N (TDF_BATCH_ATTEMPT) and then succeeds, "oom"
// exits as tdf does on std::bad_alloc, "hang" never ends by itself.
std::string fake_tdf(const std::string& folder) {
    const std::string path = folder + "/fake_tdf.sh";
    write_text_atomically(
        path,
        "#!/bin/sh\n"
        "threads=$2; cmd=$3; shift 3\n"
        "echo \"progress line\" >&2\n"
        "case \"$cmd\" in\n"
        "  compare) echo '{\"result\": \"pass\", \"overall\": {\"psnr\": 41.5, \"max_error\": 0.01}}';"
        " exit 0;;\n"
        "esac\n"
        "case \"$1\" in\n"
        "  fail) echo \"tdf $cmd: scene.json: unknown key 'colour'\" >&2; echo 'trailing' >&2; exit 1;;\n"
        "  kill) [ \"$TDF_BATCH_ATTEMPT\" -le \"$2\" ] && kill -KILL $$;"
        " out=$3; mkdir -p \"$out\"; exit 0;;\n"
        "  oom) echo \"tdf $cmd: out of memory while processing 'big.obj'\" >&2; exit 71;;\n"
        "  hang) exec sleep 600;;\n"
        "  ok) out=$3; mkdir -p \"$out\"; echo $threads > \"$out/threads.txt\"; : > \"$out/a.png\";"
        " exit 0;;\n"
        "esac\n"
        "exit 3\n");
    chmod(path.c_str(), 0755);
    return path;
}

}  // namespace

TEST(BatchEngine, ChangedManifestIsRefusedNamingTheChange) {
    const std::string root = fresh("refuse");
    const auto jobs = parse_manifest("name,command,args\na,tactile,ok x {out}\n", "m.csv");
    BatchFolder::create(root, jobs, "/bin/true", root);
    EXPECT_NO_THROW(BatchFolder::create(root, jobs, "/bin/true", root));  // same manifest: continue
    auto changed = jobs;
    changed[0].args[0] = "fail";
    try {
        BatchFolder::create(root, changed, "/bin/true", root);
        FAIL() << "a changed manifest was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("was made from another manifest: job 'a': args differ"),
                  std::string::npos)
            << e.what();
    }
}

TEST(BatchEngine, SharedOutputFoldersAreRefused) {
    const std::string root = fresh("shared_output");
    const auto jobs =
        parse_manifest("name,command,args,output\na,render,s.json,x\nb,render,s.json,x/\n", "m.csv");
    try {
        BatchFolder::create(root, jobs, "/bin/true", root);
        FAIL() << "two jobs with one output folder were accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("jobs 'a' and 'b' have the same output folder"),
                  std::string::npos)
            << e.what();
    }
}

TEST(BatchEngine, ARunningStateWhoseRunnerIsGoneReadsAsFailed) {
    const std::string root = fresh("lost");
    const auto jobs = parse_manifest("name,command,args\na,render,s.json\n", "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, "/bin/true", root);
    JobState state;
    state.status = JobStatus::Running;
    state.host = host_name();
    state.pid = getpid();
    folder.write_state(jobs[0], state);
    EXPECT_EQ(folder.read_state(jobs[0]).status, JobStatus::Running);  // this process: alive
    state.pid = 0x3fffffff;                                            // above pid_max: no such process
    folder.write_state(jobs[0], state);
    const JobState lost = folder.read_state(jobs[0]);
    EXPECT_EQ(lost.status, JobStatus::Failed);
    EXPECT_EQ(lost.end, JobEnd::FailedResource);  // the runner's node or memory, not the input
    EXPECT_EQ(lost.tries, 1);
    EXPECT_NE(lost.error.find("the runner stopped without recording a result"), std::string::npos);
}

// The finish job waits for a task that requeued itself while Slurm still lists it, and for
// nothing else (max_seconds 0: it reports what it would still wait for, without waiting).
TEST(BatchEngine, TheFinishJobWaitsOnlyForTasksThatRequeuedThemselves) {
    const std::string root = fresh("requeued");
    const auto jobs = parse_manifest("name,command,args\na,optimize,s.json\n", "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, "/bin/true", root);
    // A stand-in squeue: lists the task as PENDING, or lists nothing (Slurm forgot it).
    const std::string bin = root + "/bin";
    fs::create_directories(bin);
    const auto fake_squeue = [&](const std::string& listing) {
        write_text_atomically(bin + "/squeue", "#!/bin/sh\nprintf '" + listing + "'\n");
        chmod((bin + "/squeue").c_str(), 0755);
    };
    const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
    setenv("PATH", (bin + ":" + path).c_str(), 1);

    JobState state;
    state.end_attempt(JobEnd::Preempted);
    state.slurm_job = "7_1";
    state.requeued = true;
    folder.write_state(jobs[0], state);
    EXPECT_TRUE(folder.read_state(jobs[0]).requeued);  // the flag survives the state file

    fake_squeue("PENDING");
    EXPECT_EQ(wait_for_requeued_jobs(folder, 0), 1);  // requeued and still listed: the summary waits
    fake_squeue("");
    EXPECT_EQ(wait_for_requeued_jobs(folder, 0), 0);  // cancelled or purged: nothing will run
    fake_squeue("PENDING");
    state.requeued = false;  // scontrol requeue failed: no rerun to wait for
    folder.write_state(jobs[0], state);
    EXPECT_EQ(wait_for_requeued_jobs(folder, 0), 0);
    state.requeued = true;
    state.end_attempt(JobEnd::Done);  // the rerun has ended
    folder.write_state(jobs[0], state);
    EXPECT_EQ(wait_for_requeued_jobs(folder, 0), 0);
    setenv("PATH", path.c_str(), 1);
}

TEST(BatchEngine, ExitCodesAndSignalsClassifyAJobsEnd) {
    EXPECT_EQ(classify_job_end(1, 0, false), JobEnd::FailedInput);      // tdf::Error, usage
    EXPECT_EQ(classify_job_end(2, 0, false), JobEnd::FailedInput);      // compare: size mismatch
    EXPECT_EQ(classify_job_end(71, 0, false), JobEnd::FailedResource);  // std::bad_alloc
    EXPECT_EQ(classify_job_end(70, 0, false), JobEnd::FailedResource);  // another exception than tdf::Error
    EXPECT_EQ(classify_job_end(75, 0, false), JobEnd::Preempted);       // checkpointed on a signal
    EXPECT_EQ(classify_job_end(-1, SIGKILL, false), JobEnd::FailedResource);
    EXPECT_EQ(classify_job_end(-1, SIGSEGV, false), JobEnd::FailedResource);
    EXPECT_EQ(classify_job_end(-1, SIGTERM, false), JobEnd::Preempted);
    EXPECT_EQ(classify_job_end(75, 0, true), JobEnd::FailedResource);  // stopped at --timeout
    EXPECT_EQ(classify_job_end(-1, SIGTERM, true), JobEnd::FailedResource);
}

// A state's status follows from how its attempt ended: recorded together, they cannot disagree.
TEST(BatchEngine, AnEndedAttemptSetsClassAndStatusTogether) {
    const std::pair<JobEnd, JobStatus> expected[] = {{JobEnd::Done, JobStatus::Done},
                                                     {JobEnd::FailedInput, JobStatus::Failed},
                                                     {JobEnd::FailedResource, JobStatus::Failed},
                                                     {JobEnd::Preempted, JobStatus::Interrupted}};
    for (const auto& [end, status] : expected) {
        JobState state;
        state.status = JobStatus::Running;
        state.end_attempt(end);
        EXPECT_EQ(state.end, end) << job_end_name(end);
        EXPECT_EQ(state.status, status) << job_end_name(end);
        const JobState read = JobState::from_json(state.to_json());
        EXPECT_EQ(read.status, status) << job_end_name(end);
        EXPECT_EQ(read.end, end) << job_end_name(end);
    }
}

TEST(BatchEngine, StatesWrittenBeforeClassesGetOneFromTheirExit) {
    EXPECT_EQ(JobState::from_json({{"status", "failed"}, {"exit_code", 1}, {"attempts", 2}}).end,
              JobEnd::FailedInput);
    const JobState killed = JobState::from_json({{"status", "failed"}, {"signal", 9}, {"attempts", 2}});
    EXPECT_EQ(killed.end, JobEnd::FailedResource);
    EXPECT_EQ(killed.tries, 2);
    EXPECT_EQ(JobState::from_json({{"status", "interrupted"}}).end, JobEnd::Preempted);
    EXPECT_EQ(JobState::from_json({{"status", "done"}}).end, JobEnd::Done);
    EXPECT_EQ(JobState::from_json({{"status", "pending"}}).end, JobEnd::None);
    EXPECT_THROW(JobState::from_json({{"status", "failed"}, {"class", "failed-badly"}}), Error);
}

TEST(BatchEngine, ResourceFailuresAreRetriedAndInputFailuresAreNot) {
    const std::string root = fresh("retries");
    const auto jobs = parse_manifest(
        "name,command,args\n"
        "a,tactile,ok x {out}\n"
        "bad,tactile,fail\n"
        "once,tactile,kill 1 {out}\n"
        "always,tactile,kill 99 {out}\n"
        "oom,tactile,oom\n",
        "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, fake_tdf(root), root);
    JobRunPlan plan;
    plan.indices = {0, 1, 2, 3, 4};
    plan.parallel = 2;
    plan.max_retries = 2;
    const JobRunOutcome outcome = run_jobs(folder, plan);
    EXPECT_EQ(outcome.done, 2);
    EXPECT_EQ(outcome.failed, 3);
    EXPECT_EQ(outcome.retried, 1 + 2 + 2);
    EXPECT_EQ(outcome.not_started, 0);

    const JobState bad = folder.read_state(jobs[1]);
    EXPECT_EQ(bad.end, JobEnd::FailedInput);
    EXPECT_EQ(bad.attempts, 1);  // never retried
    EXPECT_EQ(bad.error, "tdf tactile: scene.json: unknown key 'colour'");
    const JobState once = folder.read_state(jobs[2]);
    EXPECT_EQ(once.status, JobStatus::Done);
    EXPECT_EQ(once.end, JobEnd::Done);
    EXPECT_EQ(once.attempts, 2);
    EXPECT_EQ(once.tries, 2);
    const JobState always = folder.read_state(jobs[3]);
    EXPECT_EQ(always.status, JobStatus::Failed);
    EXPECT_EQ(always.end, JobEnd::FailedResource);
    EXPECT_EQ(always.tries, 3);  // the first try and max_retries more
    EXPECT_EQ(always.signal, SIGKILL);
    EXPECT_EQ(always.error, "killed by SIGKILL: progress line");  // and the last line it printed
    const JobState oom = folder.read_state(jobs[4]);
    EXPECT_EQ(oom.end, JobEnd::FailedResource);
    EXPECT_EQ(oom.exit_code, 71);
    EXPECT_EQ(oom.tries, 3);
    EXPECT_EQ(oom.error, "tdf tactile: out of memory while processing 'big.obj'");
    EXPECT_TRUE(failed_for_good(oom, 2));
    EXPECT_FALSE(failed_for_good(oom, 3));  // a run with --max-retries 3 would try it again

    const BatchTotals totals = batch_totals(folder);
    EXPECT_EQ(totals.failed_input, 1);
    EXPECT_EQ(totals.failed_resource, 2);
    const std::string table = batch_status_table(folder);
    EXPECT_NE(table.find("5 jobs: 2 done, 3 failed, 0 interrupted, 0 running, 0 pending (1 failed-input, 2 "
                         "failed-resource)"),
              std::string::npos)
        << table;
    EXPECT_NE(table.find("failed-input"), std::string::npos);
    write_batch_summary(folder);
    const Json summary = load_json_file(root + "/summary.json");
    EXPECT_EQ(summary["jobs"][3]["class"], "failed-resource");
    EXPECT_EQ(summary["jobs"][3]["tries"], 3);
    EXPECT_EQ(summary["totals"]["failed_input"], 1);
}

TEST(BatchEngine, MaxFailuresStopsStartingJobsAndTheNextRunContinues) {
    const std::string root = fresh("max_failures");
    const auto jobs = parse_manifest(
        "name,command,args\n"
        "bad1,tactile,fail\n"
        "killed,tactile,kill 99 {out}\n"
        "a,tactile,ok x {out}\n"
        "b,tactile,ok x {out}\n",
        "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, fake_tdf(root), root);
    JobRunPlan plan;
    plan.indices = {0, 1, 2, 3};
    plan.parallel = 1;     // in manifest order: the cap is reached before a and b
    plan.max_retries = 0;  // (a retry would go to the end of the queue, after a and b)
    plan.max_failures = 2;
    const JobRunOutcome outcome = run_jobs(folder, plan);
    EXPECT_TRUE(outcome.capped);
    EXPECT_EQ(outcome.failed, 2);
    EXPECT_EQ(outcome.not_started, 2);
    EXPECT_EQ(folder.read_state(jobs[1]).tries, 1);
    EXPECT_EQ(folder.read_state(jobs[2]).status, JobStatus::Pending);
    EXPECT_EQ(folder.read_state(jobs[3]).status, JobStatus::Pending);
    EXPECT_EQ(batch_totals(folder).pending, 2);
    plan.indices = {2, 3};
    const JobRunOutcome second = run_jobs(folder, plan);
    EXPECT_EQ(second.done, 2);
    EXPECT_FALSE(second.capped);
}

TEST(BatchEngine, ATimedOutJobIsStoppedAndEndsFailedResource) {
    const std::string root = fresh("timeout");
    const auto jobs = parse_manifest("name,command,args\nslow,tactile,hang\n", "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, fake_tdf(root), root);
    JobRunPlan plan;
    plan.indices = {0};
    plan.max_retries = 0;
    plan.timeout_seconds = 0.3;  // the job never ends by itself: the outcome does not depend on speed
    const JobRunOutcome outcome = run_jobs(folder, plan);
    EXPECT_EQ(outcome.failed, 1);
    const JobState slow = folder.read_state(jobs[0]);
    EXPECT_EQ(slow.end, JobEnd::FailedResource);
    EXPECT_EQ(slow.signal, SIGTERM);
    EXPECT_EQ(slow.error.rfind("timed out after 0 s (--timeout)", 0), 0u) << slow.error;
}

TEST(BatchEngine, CommandLineAddsOutputJsonAndResume) {
    const std::string root = fresh("command_line");
    const auto jobs = parse_manifest(
        "name,command,args\n"
        "o,optimize,s.json seed=1\n"
        "r,render,s.json -o {out}/views\n"
        "c,compare,a.exr b.exr\n",
        "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, "/usr/bin/tdf", root);
    const std::string out = root + "/jobs/o";
    EXPECT_EQ(job_command_line(folder, jobs[0], 2),
              (std::vector<std::string>{
                  "/usr/bin/tdf", "--threads", "2", "optimize", "s.json", "seed=1", "-o", out}));
    EXPECT_EQ(job_command_line(folder, jobs[1], 1).back(), root + "/jobs/r/views");
    EXPECT_EQ(job_command_line(folder, jobs[2], 1).back(), "--json");
    // An interrupted optimize (checkpoint, no completion record) continues with --resume.
    write_text_atomically(out + "/checkpoint.bin", "x");
    EXPECT_EQ(job_command_line(folder, jobs[0], 2).back(), "--resume");
    write_text_atomically(out + "/pebble_complete.json", "{}");
    EXPECT_EQ(job_command_line(folder, jobs[0], 2).back(), out);
}

TEST(BatchEngine, LocalEngineRunsEveryJobAndAFailureDoesNotStopTheOthers) {
    const std::string root = fresh("local");
    const auto jobs = parse_manifest(
        "name,command,args\n"
        "a,tactile,ok x {out}\n"
        "bad,tactile,fail\n"
        "b,tactile,ok x {out}\n"
        "cmp,compare,a.exr b.exr\n"
        "d,tactile,ok x {out}\n",
        "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, fake_tdf(root), root);
    JobRunPlan plan;
    plan.indices = {0, 1, 2, 3, 4};
    plan.parallel = 2;
    plan.threads_per_job = 3;
    const JobRunOutcome outcome = run_jobs(folder, plan);
    EXPECT_EQ(outcome.done, 4);
    EXPECT_EQ(outcome.failed, 1);
    EXPECT_FALSE(outcome.stopped);
    EXPECT_EQ(read_text_file(root + "/jobs/d/threads.txt"), "3\n");

    const JobState bad = folder.read_state(jobs[1]);
    EXPECT_EQ(bad.status, JobStatus::Failed);
    EXPECT_EQ(bad.exit_code, 1);
    EXPECT_EQ(bad.error, "tdf tactile: scene.json: unknown key 'colour'");
    EXPECT_EQ(bad.attempts, 1);
    const JobState a = folder.read_state(jobs[0]);
    EXPECT_EQ(a.status, JobStatus::Done);
    EXPECT_EQ(a.thumbnail, "jobs/a/a.png");
    const JobState cmp = folder.read_state(jobs[3]);
    EXPECT_EQ(cmp.quality["psnr"].get<double>(), 41.5);
    EXPECT_EQ(cmp.quality["result"], "pass");

    const BatchTotals totals = batch_totals(folder);
    EXPECT_EQ(totals.done, 4);
    EXPECT_EQ(totals.failed, 1);
    EXPECT_EQ(totals.exit_code(), kBatchExitFailed);

    write_batch_summary(folder);
    const Json summary = load_json_file(root + "/summary.json");
    EXPECT_EQ(summary["totals"]["failed"], 1);
    EXPECT_EQ(summary["jobs"][1]["error"], "tdf tactile: scene.json: unknown key 'colour'");
    EXPECT_EQ(summary["jobs"][0]["output"], "jobs/a");
    EXPECT_EQ(summary["jobs"][0]["log"], "logs/a.log");
    const std::string csv = read_text_file(root + "/summary.csv");
    EXPECT_EQ(csv.substr(0, csv.find('\n')),
              "job,command,status,class,exit_code,signal,error,attempts,tries,seconds,seconds_total,started,"
              "finished,"
              "host,slurm_job,"
              "output,log,thumbnail,quality.max_error,quality.psnr,quality.result");
    EXPECT_NE(csv.find("\ncmp,compare,done,done,0,0,"), std::string::npos) << csv;
    EXPECT_NE(
        batch_status_table(folder).find("5 jobs: 4 done, 1 failed, 0 interrupted, 0 running, 0 pending"),
        std::string::npos);

    // The failed job again: it counts a second attempt, and its log keeps both.
    plan.indices = {1};
    run_jobs(folder, plan);
    EXPECT_EQ(folder.read_state(jobs[1]).attempts, 2);
    const std::string log = read_text_file(folder.log_path(jobs[1]));
    EXPECT_NE(log.find("attempt 1"), std::string::npos);
    EXPECT_NE(log.find("attempt 2"), std::string::npos);
}

TEST(BatchEngine, SlurmArraySpecAndScript) {
    EXPECT_EQ(slurm_array_spec({0, 1, 2, 3}, 2), "0-3%2");
    EXPECT_EQ(slurm_array_spec({1, 3, 4, 5, 9}, 0), "1,3-5,9");
    const std::string root = fresh("slurm");
    const auto jobs = parse_manifest("name,command,args\na,render,s.json\nb,render,s.json\n", "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, "/opt/tdf/bin/tdf", "/home/me/project");
    SlurmOptions options;
    options.max_parallel = 4;
    options.cpus_per_task = 8;
    options.signal_seconds = 300;
    const std::string script = slurm_array_script(folder, {0, 1}, options);
    for (const std::string& line :
         {std::string("#SBATCH --array=0-1%4\n"),
          std::string("#SBATCH --cpus-per-task=8\n"),
          std::string("#SBATCH --requeue\n"),
          std::string("#SBATCH --signal=B:USR1@300\n"),
          "#SBATCH --output=" + root + "/logs/slurm-%A_%a.out\n",
          std::string("#SBATCH --chdir=/home/me/project\n"),
          "exec '/opt/tdf/bin/tdf' batch task '" + root + "' \"$SLURM_ARRAY_TASK_ID\"\n"})
        EXPECT_NE(script.find(line), std::string::npos) << line << "\n" << script;
}

TEST(BatchEngine, ArraysAreSplitBelowMaxArraySize) {
    const auto arrays = split_array({0, 1, 2, 999, 1000, 1001, 2500}, 1000);
    ASSERT_EQ(arrays.size(), 3u);
    EXPECT_EQ(arrays[0].first, 0u);
    EXPECT_EQ(arrays[0].second, (std::vector<std::size_t>{0, 1, 2, 999}));
    EXPECT_EQ(arrays[1].first, 1000u);
    EXPECT_EQ(arrays[1].second, (std::vector<std::size_t>{0, 1}));
    EXPECT_EQ(arrays[2].first, 2000u);
    EXPECT_EQ(arrays[2].second, (std::vector<std::size_t>{500}));
    EXPECT_EQ(split_array({3, 4}, 1001).size(), 1u);

    const std::string root = fresh("slurm_split");
    const auto jobs = parse_manifest("name,command,args\na,render,s.json\n", "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, "/opt/tdf", "/home/me");
    const std::string script = slurm_array_script(folder, {0, 1}, SlurmOptions(), 1000);
    EXPECT_NE(script.find("batch task '" + root + "' \"$((1000 + SLURM_ARRAY_TASK_ID))\"\n"),
              std::string::npos)
        << script;
}

TEST(BatchEngine, RetryRoundsScaleMemoryAndTime) {
    EXPECT_EQ(scale_sbatch_option("--mem=4G", 1.5), "--mem=6144");
    EXPECT_EQ(scale_sbatch_option("--mem=1000", 2), "--mem=2000");
    EXPECT_EQ(scale_sbatch_option("--mem=512M", 1), "--mem=512");
    EXPECT_EQ(scale_sbatch_option("--time=30", 2), "--time=60");
    EXPECT_EQ(scale_sbatch_option("--time=01:30:00", 2), "--time=180");
    EXPECT_EQ(scale_sbatch_option("--time=1-00:00:00", 1.5), "--time=2160");
    EXPECT_EQ(scale_sbatch_option("--time=10:30", 1), "--time=11");  // MM:SS, rounded up
    EXPECT_EQ(scale_sbatch_option("--partition=cpu", 2), "--partition=cpu");
    SlurmOptions o;
    o.retry_mem_factor = 1.5;
    o.max_array_size = 7;
    EXPECT_EQ(SlurmOptions::from_json(o.to_json()).retry_mem_factor, 1.5);
    EXPECT_EQ(SlurmOptions::from_json(o.to_json()).max_array_size, 7);
}

TEST(BatchEngine, ResourceFailuresRecordTheirHost) {
    const std::string root = fresh("failed_hosts");
    const auto jobs = parse_manifest("name,command,args\nk,tactile,kill 99 {out}\n", "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, fake_tdf(root), root);
    JobRunPlan plan;
    plan.indices = {0};
    plan.max_retries = 1;
    run_jobs(folder, plan);
    EXPECT_EQ(folder.read_state(jobs[0]).failed_hosts, (std::vector<std::string>{host_name(), host_name()}));
}

TEST(BatchEngine, RetriesUnderSlurmAskForMoreAndAvoidNodesThatFailedTwice) {
    const std::string root = fresh("slurm_groups");
    const auto jobs =
        parse_manifest("name,command,args\na,render,s.json\nb,render,s.json\nc,render,s.json\n", "m.csv");
    const BatchFolder folder = BatchFolder::create(root, jobs, "/opt/tdf", root);
    JobState once;
    once.status = JobStatus::Failed;
    once.end = JobEnd::FailedResource;
    once.tries = 1;
    once.failed_hosts = {"n1"};
    folder.write_state(jobs[0], once);
    JobState twice = once;
    twice.tries = 2;
    twice.failed_hosts = {"n1", "n2", "n1"};
    folder.write_state(jobs[1], twice);
    SlurmOptions options;
    options.sbatch_options = {"--mem=1000", "--time=10", "--partition=cpu"};
    options.retry_mem_factor = 2;
    options.retry_time_factor = 1.5;
    const auto groups = slurm_job_groups(folder, {0, 1, 2}, options);
    ASSERT_EQ(groups.size(), 3u);
    EXPECT_EQ(groups[0].indices, (std::vector<std::size_t>{2}));  // never failed: as asked
    EXPECT_TRUE(groups[0].extra.empty());
    EXPECT_EQ(groups[1].indices, (std::vector<std::size_t>{0}));
    EXPECT_EQ(groups[1].extra, (std::vector<std::string>{"--mem=2000", "--time=15"}));
    EXPECT_EQ(groups[2].indices, (std::vector<std::size_t>{1}));
    EXPECT_EQ(groups[2].extra, (std::vector<std::string>{"--mem=4000", "--time=23", "--exclude=n1"}));
}
