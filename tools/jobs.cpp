#include "tools/jobs.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/system/errors.h"
#include "io/interrupt_cleanup.h"
#include "io/json.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "tools/cli.h"

extern char** environ;

namespace seamvox::cli {
namespace fs = std::filesystem;

const char* jobStatusName(JobStatus status) {
  switch (status) {
    case JobStatus::Done: return "done";
    case JobStatus::Skipped: return "skipped";
    default: return "failed";
  }
}

namespace {

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string stemOf(const std::string& path) { return fs::path(path).stem().string(); }

std::string hex(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

/// Hash of a file's bytes (0 when unreadable: the job fails when it runs).
std::uint64_t hashFile(const std::string& path, std::uint64_t seed) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) return 0;
  std::vector<char> buffer(std::size_t(1) << 22);
  std::uint64_t h = seed;
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), file)) > 0) h = hashBytes(buffer.data(), n, h);
  std::fclose(file);
  return h;
}

/// Faces declared in a file's header; otherwise a guess from its size that errs high.
/// Faces of an input (from its header, else guessed from its size) and the bytes of its vertex
/// properties (the declared vertices times the bytes per vertex of the first chunk's properties).
struct InputSize {
  std::uint64_t faces = 0, propertyBytes = 0;
};

InputSize estimateInput(const std::string& path) {
  std::error_code error;
  const std::uint64_t bytes = fs::file_size(path, error);
  if (error) return {};
  InputSize size;
  try {
    const auto stream = openMeshStream(path);
    size.faces = stream->expectedTriangles();
    MeshChunk chunk;
    if (stream->declaredVertices() > 0 && stream->next(chunk) && !chunk.positions.empty()) {
      std::uint64_t perVertex = 0;
      for (const VertexProperty& p : chunk.attributes.properties) perVertex += scalarSize(p.type);
      size.propertyBytes = perVertex * stream->declaredVertices();
    }
  } catch (const Error&) {
    return {};  // unreadable: the job fails at once
  }
  if (size.faces == 0) size.faces = formatFromPath(path) == MeshFormat::Draco ? bytes : bytes / 20;
  return size;
}

/// Last non-empty line of a log (the child's error message).
std::string lastLine(const std::string& text) {
  std::size_t end = text.find_last_not_of("\r\n ");
  if (end == std::string::npos) return "";
  const std::size_t begin = text.find_last_of('\n', end);
  return text.substr(begin == std::string::npos ? 0 : begin + 1, end - (begin == std::string::npos ? 0 : begin + 1) + 1);
}

/// A report parsed (an empty object when it is missing or malformed: its figures are then NaN).
JsonValue parseReport(const std::string& text, const std::string& source) {
  try {
    return parseJson(text, source);
  } catch (const InputError&) {
    return JsonValue();
  }
}

std::uint64_t reportCount(const JsonValue& report, const std::string& path) {
  const double value = report.numberAt(path);
  return value >= 0.0 ? static_cast<std::uint64_t>(value) : 0;
}

/// Reads the figures of a report into an outcome: param's (the map's quality under "quality.")
/// or the job report this runner writes (at the top level, quality = "").
void readFigures(const JsonValue& report, const std::string& quality, JobOutcome& outcome) {
  outcome.faces = reportCount(report, "faces");
  outcome.seamless = report.numberAt(quality + "seamless") == 1.0;
  outcome.maxSeamResidual = report.numberAt(quality + "maxSeamResidual");
  outcome.gradientError = report.numberAt(quality + "relativeGradientError");
  outcome.flipped = reportCount(report, quality + "flipped");
}

/// The child's own message in its log: the last line seamvox printed about the run ("seamvox
/// param: error: ...", or the reason of a usage error above the usage text), else the last line.
std::string childMessage(const std::string& log) {
  std::size_t end = log.size();
  while (end > 0) {
    const std::size_t begin = log.rfind('\n', end - 1);
    const std::size_t from = begin == std::string::npos ? 0 : begin + 1;
    if (log.compare(from, 7, "seamvox") == 0) return log.substr(from, end - from);
    if (begin == std::string::npos) break;
    end = begin;
  }
  return lastLine(log);
}

struct ChildResult {
  int exitCode = -1;  ///< -1 when killed by a signal
  int signal = 0;
  std::uint64_t peakBytes = 0;
};

/// Runs argv with stdout and stderr appended to logPath; waits with wait4 for its peak RSS.
ChildResult runChild(const std::vector<std::string>& argv, const std::string& logPath) {
  std::vector<char*> pointers;
  for (const std::string& a : argv) pointers.push_back(const_cast<char*>(a.c_str()));
  pointers.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, logPath.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, pointers.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw IoError("cannot start " + argv[0] + ": " + std::strerror(spawned));
  const int cleanupSlot = registerChild(pid);  // stopped when the runner is interrupted
  int status = 0;
  struct rusage usage {};
  while (wait4(pid, &status, 0, &usage) < 0) {
    if (errno != EINTR) {
      unregisterChild(cleanupSlot);
      throw IoError(std::string("wait4 failed: ") + std::strerror(errno));
    }
  }
  unregisterChild(cleanupSlot);
  ChildResult result;
  result.peakBytes = static_cast<std::uint64_t>(usage.ru_maxrss) * 1024u;
  if (WIFEXITED(status)) {
    result.exitCode = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.signal = WTERMSIG(status);
  }
  return result;
}

/// Adds `"key": raw` as the last member of a JSON object text.
std::string appendMember(std::string object, const std::string& key, const std::string& raw) {
  const std::size_t close = object.find_last_of('}');
  object.resize(close);
  while (!object.empty() && (object.back() == '\n' || object.back() == ' ')) object.pop_back();
  return object + ",\n  " + jsonQuote(key) + ": " + raw + "\n}\n";
}

std::string workDir(const std::string& outputDir) { return outputDir + "/.work"; }

}  // namespace

PreparedJob describeJob(const JobSpec& spec, const std::string& outputDir) {
  PreparedJob job;
  job.spec = spec;
  job.outputDir = outputDir;
  job.reportPath = outputDir + "/" + spec.name + ".json";
  if (spec.tiled) {
    for (const std::string& tile : spec.inputs) {
      job.outputs.push_back(outputDir + "/" + spec.name + "/" + stemOf(tile) + "." + spec.format);
    }
  } else {
    job.outputs.push_back(outputDir + "/" + spec.name + "." + spec.format);
  }
  return job;
}

PreparedJob prepareJob(const JobSpec& spec, const std::string& outputDir) {
  PreparedJob job = describeJob(spec, outputDir);
  std::uint64_t h = hashBytes("seamvox-job-1", 13);
  std::uint64_t faces = 0, propertyBytes = 0;
  const std::string kind = spec.tiled ? "tiles" : "mesh";
  h = hashBytes(kind.data(), kind.size(), h);
  for (const std::string& input : spec.inputs) {
    std::error_code error;
    const std::uint64_t bytes = fs::file_size(input, error);
    h = hashBytes(&bytes, sizeof bytes, h);
    h = hashFile(input, h);
    const InputSize size = estimateInput(input);
    faces += size.faces;
    propertyBytes += size.propertyBytes;
  }
  for (const std::string& arg : spec.paramArgs) h = hashBytes(arg.data(), arg.size() + 1, h);
  h = hashBytes(spec.format.data(), spec.format.size(), h);
  job.stamp = hex(h);
  job.estimateBytes = estimateJobPeakBytes(faces, spec.paramArgs, propertyBytes);
  job.outOfCoreMinimumBytes = jobOutOfCoreMinimumBytes(spec.paramArgs);
  job.upToDate = fs::exists(job.reportPath) &&
                 readText(job.reportPath).find("\"stamp\": \"" + job.stamp + "\"") != std::string::npos;
  for (const std::string& output : job.outputs) job.upToDate = job.upToDate && fs::exists(output);
  return job;
}

JobOutcome skippedOutcome(const PreparedJob& job) {
  JobOutcome outcome;
  outcome.name = job.spec.name;
  outcome.status = JobStatus::Skipped;
  outcome.estimateBytes = job.estimateBytes;
  const JsonValue report = parseReport(readText(job.reportPath), job.reportPath);
  readFigures(report, "", outcome);
  outcome.seconds = report.numberAt("seconds");
  outcome.peakBytes = reportCount(report, "peakResidentBytes");
  return outcome;
}

JobOutcome runJob(const PreparedJob& job, const RunnerOptions& options) {
  JobOutcome outcome;
  outcome.name = job.spec.name;
  outcome.estimateBytes = job.estimateBytes;
  const auto start = std::chrono::steady_clock::now();
  const std::string work = workDir(job.outputDir);
  const std::string base = work + "/" + job.spec.name;
  const std::string logPath = base + ".log";
  const std::string paramReport = base + ".param.json";
  try {
    fs::create_directories(work);
    fs::remove(job.reportPath);  // a failure must not leave an older report claiming success
    fs::remove(logPath);
    fs::remove(paramReport);
    auto step = [&](const std::vector<std::string>& args, const char* what) {
      const ChildResult child = runChild(args, logPath);
      outcome.peakBytes = std::max(outcome.peakBytes, child.peakBytes);
      if (child.exitCode == 0) return;
      std::string why = child.signal ? "killed by signal " + std::to_string(child.signal) +
                                           " (crash or out of memory)"
                                     : childMessage(readText(logPath));
      if (why.empty()) why = "exit code " + std::to_string(child.exitCode);
      throw Error(std::string(what) + ": " + why);
    };
    const std::string threads = std::to_string(std::max<std::uint32_t>(1, options.threadsPerJob));
    auto paramStep = [&](const std::string& input, const std::string& output) {
      std::vector<std::string> args = {options.executable, "param", input, "-o", output,
                                       "--report", paramReport, "--quiet", "--threads", threads};
      args.insert(args.end(), job.spec.paramArgs.begin(), job.spec.paramArgs.end());
      // The job's share of the budget is param's own budget: above its estimate it runs out of core.
      const bool budgetGiven = std::find(job.spec.paramArgs.begin(), job.spec.paramArgs.end(), "--memory-budget") !=
                               job.spec.paramArgs.end();
      if (job.reserveBytes > 0 && !budgetGiven) {
        args.push_back("--memory-budget");
        args.push_back(std::to_string(job.reserveBytes));
      }
      step(args, "param");
    };
    if (job.spec.tiled) {
      const std::string merged = base + ".merged.ply", mapped = base + ".mapped.ply";
      std::vector<std::string> weld = {options.executable, "jobs", "--weld-tiles", merged, "--quiet"};
      weld.insert(weld.end(), job.spec.inputs.begin(), job.spec.inputs.end());
      step(weld, "weld tiles");
      paramStep(merged, mapped);
      fs::remove(merged);
      std::vector<std::string> split = {options.executable, "jobs", "--split-tiles", mapped,
                                        "--tiles-output", job.outputDir + "/" + job.spec.name,
                                        "--format", job.spec.format, "--quiet"};
      split.insert(split.end(), job.spec.inputs.begin(), job.spec.inputs.end());
      step(split, "split tiles");
      fs::remove(mapped);
    } else {
      paramStep(job.spec.inputs[0], job.outputs[0]);
    }
    const std::string paramText = readText(paramReport);
    const JsonValue paramFigures = parseReport(paramText, paramReport);
    readFigures(paramFigures, "quality.", outcome);
    // wait4's peak misses param's largest stages (its meter resets the kernel's peak per stage).
    outcome.peakBytes = std::max(outcome.peakBytes, reportCount(paramFigures, "peakResidentBytes"));
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    outcome.status = JobStatus::Done;

    JsonWriter j;
    j.beginObject();
    j.key("job").value(job.spec.name).key("status").value("done").key("stamp").value(job.stamp);
    j.key("kind").value(job.spec.tiled ? "tiles" : "mesh");
    j.key("inputs").beginArray();
    for (const std::string& input : job.spec.inputs) j.value(input);
    j.endArray();
    j.key("outputs").beginArray();
    for (const std::string& output : job.outputs) j.value(output);
    j.endArray();
    j.key("paramOptions").beginArray();
    for (const std::string& arg : job.spec.paramArgs) j.value(arg);
    j.endArray();
    j.key("faces").value(outcome.faces).key("seamless").value(outcome.seamless);
    j.key("maxSeamResidual").value(outcome.maxSeamResidual);
    j.key("relativeGradientError").value(outcome.gradientError);
    j.key("flipped").value(outcome.flipped);
    j.key("seconds").value(outcome.seconds);
    j.key("peakResidentBytes").value(outcome.peakBytes);
    j.key("estimatedPeakBytes").value(outcome.estimateBytes);
    j.endObject();
    writeTextOutput(job.reportPath, appendMember(j.str(), "param", paramText));
    fs::remove(paramReport);
    fs::remove(logPath);
  } catch (const std::exception& e) {
    outcome.status = JobStatus::Failed;
    outcome.error = errorMessage(e);
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  if (!options.quiet) {
    std::fprintf(stderr, "seamvox jobs: %s %s (%.1f s)%s%s\n", job.spec.name.c_str(),
                 jobStatusName(outcome.status), outcome.seconds, outcome.error.empty() ? "" : ": ",
                 outcome.error.c_str());
  }
  return outcome;
}

std::string budgetRefusal(const PreparedJob& job, std::uint64_t budgetBytes) {
  return "estimated peak " + std::to_string(job.estimateBytes >> 20) + " MiB exceeds the memory budget of " +
         std::to_string(budgetBytes >> 20) + " MiB, and param's out-of-core path needs at least " +
         std::to_string(job.outOfCoreMinimumBytes >> 20) + " MiB at the job's grid";
}

std::vector<JobOutcome> runJobsLocally(const std::vector<PreparedJob>& jobs, std::uint32_t workers,
                                       std::uint64_t budgetBytes, const RunnerOptions& options) {
  std::vector<JobOutcome> outcomes(jobs.size());
  std::vector<std::size_t> pending;
  std::vector<std::uint64_t> reserve(jobs.size(), 0);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    reserve[i] = reserveJobMemory(jobs[i].estimateBytes, jobs[i].outOfCoreMinimumBytes, budgetBytes);
    if (reserve[i] == 0) {
      JobOutcome& o = outcomes[i];
      o.name = jobs[i].spec.name;
      o.estimateBytes = jobs[i].estimateBytes;
      o.error = budgetRefusal(jobs[i], budgetBytes);
    } else {
      pending.push_back(i);
    }
  }
  std::mutex mutex;
  std::condition_variable finished;
  std::uint64_t runningBytes = 0;
  std::uint32_t running = 0;
  std::vector<std::thread> threads;
  std::unique_lock<std::mutex> lock(mutex);
  while (!pending.empty() || running > 0) {
    std::int64_t pick = -1;
    if (running < std::max<std::uint32_t>(1, workers) && !pending.empty()) {
      std::vector<std::uint64_t> estimates;
      for (const std::size_t i : pending) estimates.push_back(reserve[i]);
      pick = pickNextJob(estimates, runningBytes, budgetBytes);
    }
    if (pick < 0) {
      finished.wait(lock);
      continue;
    }
    const std::size_t index = pending[static_cast<std::size_t>(pick)];
    pending.erase(pending.begin() + pick);
    runningBytes += reserve[index];
    ++running;
    threads.emplace_back([&, index] {
      PreparedJob job = jobs[index];
      job.reserveBytes = reserve[index];
      JobOutcome outcome = runJob(job, options);
      std::lock_guard<std::mutex> guard(mutex);
      outcomes[index] = std::move(outcome);
      runningBytes -= reserve[index];
      --running;
      finished.notify_all();
    });
  }
  lock.unlock();
  for (std::thread& t : threads) t.join();
  return outcomes;
}

std::string formatSummaryText(const std::vector<JobOutcome>& outcomes) {
  std::string text;
  char line[512];
  std::snprintf(line, sizeof line, "%-20s %-8s %10s %8s %9s %9s %-9s %10s %9s %7s  %s\n", "job", "status",
                "faces", "seconds", "peak MiB", "est. MiB", "seamless", "residual", "grad err", "flipped",
                "error");
  text += line;
  std::size_t failed = 0;
  for (const JobOutcome& o : outcomes) {
    failed += o.status == JobStatus::Failed;
    std::snprintf(line, sizeof line, "%-20s %-8s %10llu %8.2f %9.1f %9.1f %-9s %10.3g %9.4f %7llu  %s\n",
                  o.name.c_str(), jobStatusName(o.status), static_cast<unsigned long long>(o.faces),
                  o.seconds, o.peakBytes / 1048576.0, o.estimateBytes / 1048576.0,
                  o.status == JobStatus::Failed ? "-" : o.seamless ? "yes" : "NO", o.maxSeamResidual,
                  o.gradientError, static_cast<unsigned long long>(o.flipped), o.error.c_str());
    text += line;
  }
  std::snprintf(line, sizeof line, "%zu jobs: %zu failed\n", outcomes.size(), failed);
  return text + line;
}

std::string formatSummaryCsv(const std::vector<JobOutcome>& outcomes) {
  auto quote = [](const std::string& s) {
    std::string q = "\"";
    for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  std::string text =
      "job,status,faces,seconds,peak_bytes,estimated_peak_bytes,seamless,max_seam_residual,"
      "relative_gradient_error,flipped,error\n";
  char line[256];
  for (const JobOutcome& o : outcomes) {
    std::snprintf(line, sizeof line, ",%s,%llu,%.3f,%llu,%llu,%s,%.6g,%.6g,%llu,", jobStatusName(o.status),
                  static_cast<unsigned long long>(o.faces), o.seconds,
                  static_cast<unsigned long long>(o.peakBytes), static_cast<unsigned long long>(o.estimateBytes),
                  o.status == JobStatus::Failed ? "" : o.seamless ? "true" : "false", o.maxSeamResidual,
                  o.gradientError, static_cast<unsigned long long>(o.flipped));
    text += quote(o.name) + line + quote(o.error) + "\n";
  }
  return text;
}

std::string serializeOutcome(const JobOutcome& o) {
  std::ostringstream out;
  out.precision(17);
  out << o.name << '\n' << static_cast<int>(o.status) << '\n' << o.faces << '\n' << o.seconds << '\n'
      << o.peakBytes << '\n' << o.estimateBytes << '\n' << o.seamless << '\n' << o.maxSeamResidual << '\n'
      << o.gradientError << '\n' << o.flipped << '\n' << o.error;
  return out.str();
}

JobOutcome deserializeOutcome(const std::string& text) {
  std::istringstream in(text);
  JobOutcome o;
  int status = 2;
  std::string line;
  std::getline(in, o.name);
  auto next = [&]() -> std::string {
    std::getline(in, line);
    return line;
  };
  status = std::atoi(next().c_str());
  o.status = static_cast<JobStatus>(status);
  o.faces = std::strtoull(next().c_str(), nullptr, 10);
  o.seconds = std::strtod(next().c_str(), nullptr);
  o.peakBytes = std::strtoull(next().c_str(), nullptr, 10);
  o.estimateBytes = std::strtoull(next().c_str(), nullptr, 10);
  o.seamless = next() == "1";
  o.maxSeamResidual = std::strtod(next().c_str(), nullptr);
  o.gradientError = std::strtod(next().c_str(), nullptr);
  o.flipped = std::strtoull(next().c_str(), nullptr, 10);
  std::getline(in, o.error, '\0');
  return o;
}

bool isStartedByMpirun() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"}) {
    const char* value = std::getenv(name);
    if (value && std::atoi(value) > 1) return true;
  }
  return false;
}

}  // namespace seamvox::cli
