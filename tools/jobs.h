#pragma once
/// The job runner behind `seamvox jobs` (manifest format: core/batch/jobs.h). Every job runs as child
/// processes of the seamvox binary (`seamvox param`, and for tiles the weld and split steps), so
/// a crashing or out-of-memory job cannot take the runner down; peak memory comes from wait4.
#include <cstdint>
#include <string>
#include <vector>

#include "core/batch/jobs.h"

namespace seamvox::cli {

enum class JobStatus { Done, Skipped, Failed };
const char* jobStatusName(JobStatus status);

/// What one job did (or, when skipped, what its existing report says).
struct JobOutcome {
  std::string name;
  JobStatus status = JobStatus::Failed;
  std::string error;  ///< why it failed (the child's error line, a signal, the budget)
  std::uint64_t faces = 0;
  double seconds = 0.0;
  std::uint64_t peakBytes = 0;      ///< largest child peak RSS (wait4)
  std::uint64_t estimateBytes = 0;  ///< the scheduler's estimate
  bool seamless = false;
  double maxSeamResidual = 0.0, gradientError = 0.0;
  std::uint64_t flipped = 0;
};

/// A job ready to run: outputs, report path, the stamp of its inputs and options, the estimate.
struct PreparedJob {
  JobSpec spec;
  std::string outputDir;
  std::string reportPath;
  std::vector<std::string> outputs;
  std::string stamp;  ///< hash of the inputs' sizes and bytes, the options and the format
  std::uint64_t estimateBytes = 0;  ///< param's in-memory estimate (estimateJobPeakBytes)
  std::uint64_t outOfCoreMinimumBytes = 0;  ///< param's out-of-core minimum at the job's grid
  /// What the job holds of the budget while it runs (reserveJobMemory), given to param as its
  /// --memory-budget (0: param's own default); above the estimate param runs out of core.
  std::uint64_t reserveBytes = 0;
  bool upToDate = false;  ///< report and outputs exist and the report carries this stamp
};

/// The job's output and report paths (no file access; stamp and estimate left empty).
PreparedJob describeJob(const JobSpec& spec, const std::string& outputDir);
/// Hashes the inputs, estimates the peak and checks for an up-to-date earlier run. Never throws
/// for unreadable inputs (the job then fails when it runs).
PreparedJob prepareJob(const JobSpec& spec, const std::string& outputDir);
/// Why a job cannot run within the budget (reserveJobMemory gave 0).
std::string budgetRefusal(const PreparedJob& job, std::uint64_t budgetBytes);
/// The outcome recorded in an up-to-date job's report (status Skipped).
JobOutcome skippedOutcome(const PreparedJob& job);

struct RunnerOptions {
  std::string executable;          ///< the seamvox binary to launch
  std::uint32_t threadsPerJob = 1;
  bool quiet = false;              ///< no per-job progress lines
};

/// Runs one job to the end: child steps, then the report written atomically. Job errors end up
/// in the outcome, never as exceptions.
JobOutcome runJob(const PreparedJob& job, const RunnerOptions& options);

/// Runs the jobs with up to `workers` at once, starting the first pending job whose estimate fits
/// next to the running ones (pickNextJob); a job larger than the budget fails without running.
std::vector<JobOutcome> runJobsLocally(const std::vector<PreparedJob>& jobs, std::uint32_t workers,
                                       std::uint64_t budgetBytes, const RunnerOptions& options);

/// Summary table: printed text and CSV (one row per job).
std::string formatSummaryText(const std::vector<JobOutcome>& outcomes);
std::string formatSummaryCsv(const std::vector<JobOutcome>& outcomes);

/// One line per outcome field, for sending between MPI ranks.
std::string serializeOutcome(const JobOutcome& outcome);
JobOutcome deserializeOutcome(const std::string& text);

/// Whether this binary was built with MPI, and whether mpirun (or srun) started this process with
/// more than one rank (from the environment).
bool isMpiBuilt();
bool isStartedByMpirun();
/// Distributes the jobs over MPI ranks: rank 0 prepares them and hands them out one at a time to
/// the other ranks as they become free, then gathers the outcomes (returned on rank 0 only; other
/// ranks return empty with isRoot false). Needs at least 2 ranks. Throws Error without MPI.
std::vector<JobOutcome> runJobsWithMpi(const std::vector<JobSpec>& specs, const std::string& outputDir,
                                       bool force, std::uint64_t budgetBytes,
                                       const RunnerOptions& options, bool& isRoot);

}  // namespace seamvox::cli
