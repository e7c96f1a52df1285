// Distribution of `seamvox jobs` over MPI ranks. Compiled with MPI when CMake finds it
// (SEAMVOX_WITH_MPI); without it the entry point explains how to get it.
#include <string>
#include <vector>

#include "core/system/errors.h"
#include "tools/jobs.h"

#ifdef SEAMVOX_WITH_MPI
#include <mpi.h>

#include <deque>
#include <sstream>
#endif

namespace seamvox::cli {

#ifndef SEAMVOX_WITH_MPI

bool isMpiBuilt() { return false; }

std::vector<JobOutcome> runJobsWithMpi(const std::vector<JobSpec>&, const std::string&, bool, std::uint64_t,
                                       const RunnerOptions&, bool& isRoot) {
  isRoot = true;
  throw Error("this seamvox was built without MPI, so it cannot distribute jobs over ranks: install "
              "Open MPI (Debian: libopenmpi-dev openmpi-bin) and rebuild, or run without mpirun");
}

#else

namespace {

// Messages: a worker sends Ready once, then Result after each job; rank 0 answers each with Job
// ("index\nstamp\nestimate") or Stop.
enum Tag : int { kReady = 1, kResult = 2, kJob = 3, kStop = 4 };

void sendText(const std::string& text, int to, int tag) {
  MPI_Send(text.data(), static_cast<int>(text.size()), MPI_CHAR, to, tag, MPI_COMM_WORLD);
}

/// Receives the next message from `from` (MPI_ANY_SOURCE allowed) with its tag and source.
std::string receiveText(int from, int& tag, int& source) {
  MPI_Status status;
  MPI_Probe(from, MPI_ANY_TAG, MPI_COMM_WORLD, &status);
  int count = 0;
  MPI_Get_count(&status, MPI_CHAR, &count);
  std::string text(static_cast<std::size_t>(count), '\0');
  MPI_Recv(text.data(), count, MPI_CHAR, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  tag = status.MPI_TAG;
  source = status.MPI_SOURCE;
  return text;
}

std::vector<JobOutcome> handOutJobs(const std::vector<JobSpec>& specs, const std::string& outputDir,
                                    bool force, std::uint64_t budgetBytes, int ranks) {
  std::vector<JobOutcome> outcomes(specs.size());
  std::vector<PreparedJob> jobs;
  std::deque<std::size_t> queue;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    jobs.push_back(prepareJob(specs[i], outputDir));
    jobs[i].reserveBytes = reserveJobMemory(jobs[i].estimateBytes, jobs[i].outOfCoreMinimumBytes, budgetBytes);
    if (jobs[i].upToDate && !force) {
      outcomes[i] = skippedOutcome(jobs[i]);
    } else if (jobs[i].reserveBytes == 0) {
      outcomes[i].name = specs[i].name;
      outcomes[i].estimateBytes = jobs[i].estimateBytes;
      outcomes[i].error = budgetRefusal(jobs[i], budgetBytes);
    } else {
      queue.push_back(i);
    }
  }
  int active = ranks - 1;
  while (active > 0) {
    int tag = 0, source = 0;
    const std::string text = receiveText(MPI_ANY_SOURCE, tag, source);
    if (tag == kResult) {
      const std::size_t newline = text.find('\n');
      const std::size_t index = std::stoul(text.substr(0, newline));
      outcomes[index] = deserializeOutcome(text.substr(newline + 1));
    }
    if (queue.empty()) {
      sendText("", source, kStop);
      --active;
      continue;
    }
    const std::size_t index = queue.front();
    queue.pop_front();
    sendText(std::to_string(index) + "\n" + jobs[index].stamp + "\n" + std::to_string(jobs[index].estimateBytes) +
                 "\n" + std::to_string(jobs[index].reserveBytes),
             source, kJob);
  }
  return outcomes;
}

void runHandedJobs(const std::vector<JobSpec>& specs, const std::string& outputDir, const RunnerOptions& options) {
  sendText("", 0, kReady);
  while (true) {
    int tag = 0, source = 0;
    const std::string text = receiveText(0, tag, source);
    if (tag == kStop) return;
    std::istringstream in(text);
    std::size_t index = 0;
    PreparedJob job;
    std::string stamp;
    std::uint64_t estimate = 0, reserve = 0;
    in >> index >> stamp >> estimate >> reserve;
    job = describeJob(specs.at(index), outputDir);
    job.stamp = stamp;
    job.estimateBytes = estimate;
    job.reserveBytes = reserve;
    sendText(std::to_string(index) + "\n" + serializeOutcome(runJob(job, options)), 0, kResult);
  }
}

}  // namespace

bool isMpiBuilt() { return true; }

std::vector<JobOutcome> runJobsWithMpi(const std::vector<JobSpec>& specs, const std::string& outputDir,
                                       bool force, std::uint64_t budgetBytes, const RunnerOptions& options,
                                       bool& isRoot) {
  MPI_Init(nullptr, nullptr);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  isRoot = rank == 0;
  if (ranks < 2) {
    MPI_Finalize();
    throw Error("MPI distribution needs at least 2 ranks (rank 0 hands out jobs): mpirun -np K with K >= 2");
  }
  std::vector<JobOutcome> outcomes;
  if (isRoot) {
    outcomes = handOutJobs(specs, outputDir, force, budgetBytes, ranks);
  } else {
    runHandedJobs(specs, outputDir, options);
  }
  MPI_Finalize();
  return outcomes;
}

#endif

}  // namespace seamvox::cli
