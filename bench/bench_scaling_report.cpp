// Scaling-study report (issue #7): reads the per-run JSON files that bench/scaling.sh leaves in
// RUNS_DIR and writes the CSV, the markdown section for bench/RESULTS.md and a log-log PNG plot
// (total time and peak RSS against faces, one colour and marker per solver, solid lines for the
// first mesh, dashed for the second), then prints where voxloc128 (and voxloc64) overtake hat and
// the ratios at the largest size both solved.
//   bench_scaling_report RUNS_DIR [--csv F] [--md F] [--png F] [--png-link L] [--limit-gb G]
//                        [--command TEXT]
//   bench_scaling_report --self-check
// A run file is named <mesh>_L<level>_<solver>.json (solver: hat, vox64, vox128, voxloc64,
// voxloc128): either the report of `seamvox param --report`, or a stub written by the driver for
// a run that did not finish: {"status": "failed"|"skipped", "reason": "...", "faces": N, ...}.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/system/blas_threads.h"
#include "core/system/errors.h"
#include "core/synth/render.h"
#include "io/atomic_file.h"
#include "io/json.h"
#include "io/json_reader.h"
#include "io/png_io.h"

using namespace seamvox;

namespace {

// Reports are read through io/json_reader, flattened to "a.b.c" (arrays: "a.0") -> scalar.
using FlatJson = std::map<std::string, JsonValue>;
FlatJson parseFlatJson(const std::string& text, const std::string& source) {
  return flattenJson(parseJson(text, source));
}

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw IoError(path + ": read error");
  return s.str();
}

void writeTextFile(const std::string& path, const std::string& text) {
  AtomicFile file(path);
  file.write(text);
  file.commit();
}

// ---------------------------------------------------------------------------------------------
// Runs

const std::array<const char*, 5> kSolvers = {"hat", "vox64", "vox128", "voxloc64", "voxloc128"};

struct Run {
  std::string file, mesh, solver;
  int level = 0;
  std::string status = "ok";  // ok, failed, skipped
  std::string reason;
  FlatJson json;
  double number(const std::string& key) const {
    const auto it = json.find(key);
    if (it == json.end() || !it->second.isNumber()) return std::nan("");
    return it->second.number;
  }
  std::string text(const std::string& key) const {
    const auto it = json.find(key);
    if (it == json.end()) return "";
    if (it->second.type == JsonValue::Type::String) return it->second.text;
    if (it->second.type == JsonValue::Type::Bool) return it->second.flag ? "true" : "false";
    return "";
  }
  bool ok() const { return status == "ok"; }
  double faces() const { return number("faces"); }
  double total() const { return number("seconds.total"); }
  double peak() const { return number("peakResidentBytes"); }
  double l2() const { return number("quality.relativeGradientError"); }
};

/// Solver stages of the param pipeline (everything between the cut and the metrics).
const std::array<const char*, 8> kSolveStages = {"basis", "reduce", "assemble", "firstSolve",
                                                  "round", "secondSolve", "evaluate", "refine"};
double solveSeconds(const Run& r) {
  double s = 0.0;
  for (const char* stage : kSolveStages) {
    const double v = r.number(std::string("seconds.") + stage);
    if (std::isfinite(v)) s += v;
  }
  return r.ok() ? s : std::nan("");
}

int solverRank(const std::string& solver) {
  for (std::size_t i = 0; i < kSolvers.size(); ++i) {
    if (solver == kSolvers[i]) return int(i);
  }
  return int(kSolvers.size());
}

/// Parses "<mesh>_L<level>_<solver>.json"; false for other names.
bool parseRunName(const std::string& name, Run& run) {
  if (name.size() < 6 || name.compare(name.size() - 5, 5, ".json") != 0) return false;
  const std::string stem = name.substr(0, name.size() - 5);
  const std::size_t last = stem.rfind('_');
  if (last == std::string::npos || last == 0) return false;
  const std::size_t mid = stem.rfind('_', last - 1);
  if (mid == std::string::npos || mid == 0) return false;
  const std::string levelText = stem.substr(mid + 1, last - mid - 1);
  if (levelText.size() < 2 || levelText[0] != 'L') return false;
  for (std::size_t i = 1; i < levelText.size(); ++i) {
    if (levelText[i] < '0' || levelText[i] > '9') return false;
  }
  run.mesh = stem.substr(0, mid);
  run.level = std::atoi(levelText.c_str() + 1);
  run.solver = stem.substr(last + 1);
  return !run.solver.empty();
}

/// The driver's measurement of a run from outside the process (`wallSeconds=S maxRssBytes=B`,
/// /usr/bin/time), when present: fills wallSeconds, and peakResidentBytes when the run has none.
void readTimeFile(const std::filesystem::path& path, Run& run) {
  std::ifstream in(path);
  std::string item;
  while (in >> item) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = item.substr(0, eq);
    char* end = nullptr;
    const double v = std::strtod(item.c_str() + eq + 1, &end);
    if (end == item.c_str() + eq + 1 || !std::isfinite(v)) continue;
    JsonValue x;
    x.type = JsonValue::Type::Number;
    x.number = v;
    if (key == "wallSeconds" && !run.json.count("wallSeconds")) run.json["wallSeconds"] = x;
    if (key == "maxRssBytes" && !std::isfinite(run.peak())) run.json["peakResidentBytes"] = x;
  }
}

std::vector<Run> loadRuns(const std::string& dir) {
  std::vector<Run> runs;
  std::error_code ec;
  std::filesystem::directory_iterator it(dir, ec);
  if (ec) throw IoError(dir + ": cannot list the runs folder (" + ec.message() + ")");
  for (const auto& entry : it) {
    Run run;
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || !parseRunName(name, run)) continue;
    run.file = entry.path().string();
    run.json = parseFlatJson(readTextFile(run.file), run.file);
    const std::string status = run.text("status");
    if (!status.empty()) run.status = status;
    run.reason = run.text("reason");
    readTimeFile(entry.path().parent_path() / (name.substr(0, name.size() - 5) + ".time"), run);
    if (run.ok() && !std::isfinite(run.total())) {
      run.status = "failed";
      run.reason = "report without seconds.total";
    }
    if (run.ok() && run.text("solverUsed") != "" && run.text("solver") != run.text("solverUsed")) {
      run.reason = "fell back to " + run.text("solverUsed") + ": " + run.text("fallbackReason");
    }
    runs.push_back(std::move(run));
  }
  // Meshes by their smallest size, then level, then solver.
  std::map<std::string, double> meshSize;
  for (const Run& r : runs) {
    const double f = std::isfinite(r.faces()) ? r.faces() : 1e300;
    auto [pos, inserted] = meshSize.emplace(r.mesh, f);
    if (!inserted) pos->second = std::min(pos->second, f);
  }
  std::sort(runs.begin(), runs.end(), [&](const Run& a, const Run& b) {
    if (a.mesh != b.mesh) {
      const double fa = meshSize[a.mesh], fb = meshSize[b.mesh];
      return fa != fb ? fa < fb : a.mesh < b.mesh;
    }
    if (a.level != b.level) return a.level < b.level;
    return solverRank(a.solver) != solverRank(b.solver) ? solverRank(a.solver) < solverRank(b.solver)
                                                          : a.solver < b.solver;
  });
  return runs;
}

std::vector<std::string> meshesOf(const std::vector<Run>& runs) {
  std::vector<std::string> meshes;
  for (const Run& r : runs) {
    if (std::find(meshes.begin(), meshes.end(), r.mesh) == meshes.end()) meshes.push_back(r.mesh);
  }
  return meshes;
}

const Run* findRun(const std::vector<Run>& runs, const std::string& mesh, int level, const std::string& solver) {
  for (const Run& r : runs) {
    if (r.mesh == mesh && r.level == level && r.solver == solver) return &r;
  }
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// CSV

std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string csvNumber(double v) {
  if (!std::isfinite(v)) return "";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

const std::array<const char*, 15> kStageColumns = {"read", "clean", "field", "cut", "basis",
                                                   "reduce", "assemble", "firstSolve", "round",
                                                   "secondSolve", "evaluate", "refine", "metrics",
                                                   "write", "total"};
const std::array<const char*, 15> kNumberColumns = {
    "vertices", "cones", "system.unknowns", "system.positional", "system.translational",
    "system.matrixNonzeros", "system.factorNonzeros", "system.factorBytes", "voxel.elements",
    "quality.relativeGradientError", "quality.maxSeamResidual", "quality.flipped",
    "quality.flippedFraction", "quality.collapsed", "refine.refinedVertexFraction"};

std::string writeCsv(const std::vector<Run>& runs) {
  std::string out = "mesh,level,solver,status,reason,faces,solverUsed,seamless";
  for (const char* c : kStageColumns) out += std::string(",seconds.") + c;
  out += ",solveSeconds,peakResidentBytes,wallSeconds";
  for (const char* c : kNumberColumns) out += std::string(",") + c;
  out += "\n";
  for (const Run& r : runs) {
    out += csvField(r.mesh) + "," + std::to_string(r.level) + "," + csvField(r.solver) + "," +
           csvField(r.status) + "," + csvField(r.reason) + "," + csvNumber(r.faces()) + "," +
           csvField(r.text("solverUsed")) + "," + csvField(r.text("quality.seamless"));
    for (const char* c : kStageColumns) out += "," + csvNumber(r.number(std::string("seconds.") + c));
    out += "," + csvNumber(solveSeconds(r)) + "," + csvNumber(r.peak()) + "," + csvNumber(r.number("wallSeconds"));
    for (const char* c : kNumberColumns) out += "," + csvNumber(r.number(c));
    out += "\n";
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Analysis: crossover (log-log interpolation) and ratios

/// One (faces, value) series, sorted by faces, finite positive values only.
using Series = std::vector<std::pair<double, double>>;

Series seriesOf(const std::vector<Run>& runs, const std::string& mesh, const std::string& solver,
                double (*value)(const Run&)) {
  Series s;
  for (const Run& r : runs) {
    if (r.mesh != mesh || r.solver != solver || !r.ok()) continue;
    const double f = r.faces(), v = value(r);
    if (f > 0 && v > 0 && std::isfinite(f) && std::isfinite(v)) s.emplace_back(f, v);
  }
  std::sort(s.begin(), s.end());
  return s;
}

double totalOf(const Run& r) { return r.total(); }
double peakOf(const Run& r) { return r.peak(); }
double solveOf(const Run& r) { return solveSeconds(r); }

struct Crossover {
  enum class Kind { None, Below, At, NotReached } kind = Kind::None;
  double faces = 0.0;  ///< At: the interpolated size; Below: smallest common; NotReached: largest
};

/// Where `fast` first becomes cheaper than `slow`, on the sizes both have, interpolating
/// log(fast / slow) linearly in log(faces) between the last size where fast is not cheaper and
/// the next one.
Crossover findCrossover(const Series& fast, const Series& slow) {
  std::vector<std::pair<double, double>> diff;  // (log faces, log fast - log slow)
  for (const auto& [f, v] : fast) {
    for (const auto& [g, w] : slow) {
      if (f == g) diff.emplace_back(std::log(f), std::log(v) - std::log(w));
    }
  }
  Crossover c;
  if (diff.empty()) return c;
  if (diff.front().second < 0.0) {
    c.kind = Crossover::Kind::Below;
    c.faces = std::exp(diff.front().first);
    return c;
  }
  for (std::size_t i = 0; i + 1 < diff.size(); ++i) {
    const auto [x0, d0] = diff[i];
    const auto [x1, d1] = diff[i + 1];
    if (d0 >= 0.0 && d1 < 0.0) {
      c.kind = Crossover::Kind::At;
      c.faces = std::exp(x0 + (x1 - x0) * d0 / (d0 - d1));
      return c;
    }
  }
  c.kind = Crossover::Kind::NotReached;
  c.faces = std::exp(diff.back().first);
  return c;
}

std::string formatCount(double n) {
  if (!std::isfinite(n)) return "-";
  const auto v = static_cast<long long>(std::llround(n));
  std::string digits = std::to_string(v < 0 ? -v : v), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return (v < 0 ? "-" : "") + out;
}

std::string formatFixed(double v, int digits) {
  if (!std::isfinite(v)) return "-";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

/// Seconds with three significant digits (at least two decimals below 10 s).
std::string formatSeconds(double s) {
  if (!std::isfinite(s)) return "-";
  return formatFixed(s, s < 10 ? 2 : s < 100 ? 1 : 0) + " s";
}

std::string formatBytes(double b) {
  if (!std::isfinite(b)) return "-";
  if (b >= 1e9) return formatFixed(b / 1e9, 2) + " GB";
  return formatFixed(b / 1e6, b >= 1e8 ? 0 : 1) + " MB";
}

double roundSignificant(double v, int digits) {
  if (!(v > 0) || !std::isfinite(v)) return v;
  const double scale = std::pow(10.0, digits - 1 - int(std::floor(std::log10(v))));
  return std::round(v * scale) / scale;
}

std::string describeCrossover(const Crossover& c, const std::string& what) {
  switch (c.kind) {
    case Crossover::Kind::None: return "no size has both runs";
    case Crossover::Kind::Below:
      return "already " + what + " at the smallest common size (" + formatCount(c.faces) + " faces)";
    case Crossover::Kind::At:
      return what + " from about " + formatCount(roundSignificant(c.faces, 2)) + " faces (log-log interpolation)";
    case Crossover::Kind::NotReached:
      return "not " + what + " up to " + formatCount(c.faces) + " faces";
  }
  return "";
}

/// The summary lines (markdown list items without the "* ").
std::vector<std::string> summarize(const std::vector<Run>& runs, double limitGb) {
  std::vector<std::string> lines;
  for (const std::string& mesh : meshesOf(runs)) {
    for (const char* solver : {"voxloc128", "voxloc64"}) {
      const std::string name = solver;
      if (seriesOf(runs, mesh, name, totalOf).empty()) continue;
      auto crossover = [&](double (*value)(const Run&)) {
        return findCrossover(seriesOf(runs, mesh, name, value), seriesOf(runs, mesh, "hat", value));
      };
      lines.push_back(mesh + ", " + name + " vs hat: total time " +
                      describeCrossover(crossover(totalOf), "faster") + "; solver stages " +
                      describeCrossover(crossover(solveOf), "faster") + "; peak RSS " +
                      describeCrossover(crossover(peakOf), "smaller"));
      // Ratios at the largest size where both finished.
      const Run* hat = nullptr;
      const Run* loc = nullptr;
      for (const Run& r : runs) {
        if (r.mesh != mesh || r.solver != "hat" || !r.ok()) continue;
        const Run* other = findRun(runs, mesh, r.level, name);
        if (other && other->ok() && (!hat || r.level > hat->level)) {
          hat = &r;
          loc = other;
        }
      }
      if (hat) {
        lines.push_back(mesh + " at " + formatCount(hat->faces()) + " faces (largest size both ran): hat / " + name +
                        ": total time " + formatFixed(hat->total() / loc->total(), 2) + "x, solver stages " +
                        formatFixed(solveSeconds(*hat) / solveSeconds(*loc), 2) + "x, peak RSS " +
                        formatFixed(hat->peak() / loc->peak(), 2) + "x; " + name + " L2 error " +
                        formatFixed(loc->l2() / hat->l2(), 3) + "x hat's");
      }
    }
    // Where hat stopped.
    const Run* lastHat = nullptr;
    const Run* stopped = nullptr;
    for (const Run& r : runs) {
      if (r.mesh != mesh || r.solver != "hat") continue;
      if (r.ok()) lastHat = &r;
      else if (!stopped) stopped = &r;
    }
    if (lastHat) {
      std::string line = mesh + ": largest hat run " + formatCount(lastHat->faces()) + " faces (peak " +
                         formatBytes(lastHat->peak()) + ", limit " + formatBytes(limitGb * 1e9) + ")";
      if (stopped) {
        line += "; " + formatCount(stopped->faces()) + " faces: " + stopped->status +
                (stopped->reason.empty() ? "" : " (" + stopped->reason + ")");
      } else {
        line += "; no larger size was attempted";
      }
      lines.push_back(line);
    }
  }
  return lines;
}

// ---------------------------------------------------------------------------------------------
// Markdown

std::string writeMarkdown(const std::vector<Run>& runs, const std::vector<std::string>& summary,
                          const std::string& pngLink, const std::string& command) {
  std::string md;
  if (!command.empty()) md += "```\n" + command + "\n```\n\n";
  if (!pngLink.empty()) md += "![total time and peak RSS against faces, log-log](" + pngLink + ")\n\n";
  for (const std::string& line : summary) md += "* " + line + "\n";
  md += "\n";
  for (const std::string& mesh : meshesOf(runs)) {
    md += "**" + mesh + "**\n\n";
    md += "| faces | solver | total | field | basis + reduce | assemble | solves | refine | peak RSS | "
          "unknowns | factor | L2 (vs hat) | flips | refined | status |\n";
    md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Run& r : runs) {
      if (r.mesh != mesh) continue;
      const std::string faces = formatCount(r.faces());
      if (!r.ok()) {
        md += "| " + faces + " | " + r.solver + " | - | - | - | - | - | - | " + formatBytes(r.peak()) +
              " | - | - | - | - | - | " + r.status + (r.reason.empty() ? "" : ": " + r.reason) + " |\n";
        continue;
      }
      auto sec = [&](std::initializer_list<const char*> stages) {
        double s = 0;
        for (const char* st : stages) s += r.number(std::string("seconds.") + st);
        return formatSeconds(s);
      };
      std::string l2 = formatFixed(r.l2(), 4);
      const Run* hat = findRun(runs, mesh, r.level, "hat");
      if (r.solver != "hat" && hat && hat->ok()) l2 += " (" + formatFixed(r.l2() / hat->l2(), 3) + ")";
      const double refined = r.number("refine.refinedVertexFraction");
      std::string status = r.text("quality.seamless") == "true" ? "seamless" : "NOT seamless";
      if (!r.reason.empty()) status += "; " + r.reason;
      md += "| " + faces + " | " + r.solver + " | **" + formatSeconds(r.total()) + "** | " + sec({"field"}) + " | " +
            sec({"basis", "reduce"}) + " | " + sec({"assemble"}) + " | " + sec({"firstSolve", "round", "secondSolve"}) +
            " | " + sec({"refine"}) + " | **" + formatBytes(r.peak()) + "** | " + formatCount(r.number("system.unknowns")) +
            " | " + formatBytes(r.number("system.factorBytes")) + " | " + l2 + " | " +
            formatCount(r.number("quality.flipped")) + " | " +
            (std::isfinite(refined) ? formatFixed(100.0 * refined, 1) + "%" : "-") + " | " + status + " |\n";
    }
    md += "\n";
  }
  return md;
}

// ---------------------------------------------------------------------------------------------
// Plot: a small canvas with anti-aliased lines and markers and a 5x7 bitmap font.

struct Point {
  double x = 0, y = 0;
};

/// 5x7 glyphs, rows top to bottom, '1' = ink.
const std::map<char, const char*>& fontGlyphs() {
  static const std::map<char, const char*> glyphs = {
      {'0', "01110100011001110101110011000101110"}, {'1', "00100011000010000100001000010001110"},
      {'2', "01110100010000100010001000100011111"}, {'3', "11111000100010000010000011000101110"},
      {'4', "00010001100101010010111110001000010"}, {'5', "11111100001111000001000011000101110"},
      {'6', "00110010001000011110100011000101110"}, {'7', "11111000010001000100010000100001000"},
      {'8', "01110100011000101110100011000101110"}, {'9', "01110100011000101111000010001001100"},
      {'A', "01110100011000111111100011000110001"}, {'B', "11110100011000111110100011000111110"},
      {'C', "01110100011000010000100001000101110"}, {'D', "11100100101000110001100011001011100"},
      {'E', "11111100001000011110100001000011111"}, {'F', "11111100001000011110100001000010000"},
      {'G', "01110100011000010111100011000101111"}, {'H', "10001100011000111111100011000110001"},
      {'I', "01110001000010000100001000010001110"}, {'J', "00111000100001000010000101001001100"},
      {'K', "10001100101010011000101001001010001"}, {'L', "10000100001000010000100001000011111"},
      {'M', "10001110111010110101100011000110001"}, {'N', "10001100011100110101100111000110001"},
      {'O', "01110100011000110001100011000101110"}, {'P', "11110100011000111110100001000010000"},
      {'Q', "01110100011000110001101011001001101"}, {'R', "11110100011000111110101001001010001"},
      {'S', "01111100001000001110000010000111110"}, {'T', "11111001000010000100001000010000100"},
      {'U', "10001100011000110001100011000101110"}, {'V', "10001100011000110001100010101000100"},
      {'W', "10001100011000110101101011010101010"}, {'X', "10001100010101000100010101000110001"},
      {'Y', "10001100010101000100001000010000100"}, {'Z', "11111000010001000100010001000011111"},
      {'a', "00000000000111000001011111000101111"}, {'b', "10000100001011011001100011000111110"},
      {'c', "00000000000111010000100001000101110"}, {'d', "00001000010110110011100011000101111"},
      {'e', "00000000000111010001111111000001110"}, {'f', "00110010010100011100010000100001000"},
      {'g', "00000011111000110001011110000101110"}, {'h', "10000100001011011001100011000110001"},
      {'i', "00100000000110000100001000010001110"}, {'j', "00010000000011000010000101001001100"},
      {'k', "10000100001001010100110001010010010"}, {'l', "01100001000010000100001000010001110"},
      {'m', "00000000001101010101101011000110001"}, {'n', "00000000001011011001100011000110001"},
      {'o', "00000000000111010001100011000101110"}, {'p', "00000000001111010001111101000010000"},
      {'q', "00000000000110110011011110000100001"}, {'r', "00000000001011011001100001000010000"},
      {'s', "00000000000111010000011100000111110"}, {'t', "01000010001110001000010000100100110"},
      {'u', "00000000001000110001100011001101101"}, {'v', "00000000001000110001100010101000100"},
      {'w', "00000000001000110001101011010101010"}, {'x', "00000000001000101010001000101010001"},
      {'y', "00000000001000110001011110000101110"}, {'z', "00000000001111100010001000100011111"},
      {' ', "00000000000000000000000000000000000"}, {'.', "00000000000000000000000000110001100"},
      {',', "00000000000000000000011000010001000"}, {':', "00000011000110000000011000110000000"},
      {'(', "00010001000100001000010000010000010"}, {')', "01000001000001000010000100010001000"},
      {'-', "00000000000000011111000000000000000"}, {'+', "00000001000010011111001000010000000"},
      {'/', "00001000010001000100010001000010000"}, {'%', "11000110010001000100010001001100011"},
      {'^', "00100010101000100000000000000000000"}, {'=', "00000000001111100000111110000000000"},
      {'_', "00000000000000000000000000000011111"}, {'<', "00010001000100010000010000010000010"},
      {'>', "01000001000001000001000100010001000"}, {'*', "00000001001010101110101010010000000"},
  };
  return glyphs;
}

bool fontHas(char c) { return fontGlyphs().count(c) > 0; }

class Canvas {
 public:
  Canvas(std::uint32_t width, std::uint32_t height, Rgb background) {
    image_.width = width;
    image_.height = height;
    image_.pixels.resize(3 * std::size_t(width) * height);
    for (std::size_t i = 0; i < std::size_t(width) * height; ++i) {
      for (int k = 0; k < 3; ++k) image_.pixels[3 * i + k] = background[k];
    }
  }
  const RgbImage& image() const { return image_; }

  void blend(int x, int y, Rgb c, double alpha) {
    if (x < 0 || y < 0 || x >= int(image_.width) || y >= int(image_.height) || alpha <= 0) return;
    alpha = std::min(alpha, 1.0);
    std::uint8_t* p = &image_.pixels[3 * (std::size_t(y) * image_.width + x)];
    for (int k = 0; k < 3; ++k) p[k] = std::uint8_t(std::lround(p[k] + alpha * (c[k] - p[k])));
  }

  void fillRect(int x0, int y0, int x1, int y1, Rgb c) {
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) blend(x, y, c, 1.0);
    }
  }

  /// Anti-aliased segment of the given width; dash > 0 draws dash-long pieces with dash-long gaps
  /// (the pattern starts at a).
  void line(Point a, Point b, double width, Rgb c, double dash = 0.0) {
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy, len = std::sqrt(len2);
    const double r = width / 2 + 1;
    const int x0 = int(std::floor(std::min(a.x, b.x) - r)), x1 = int(std::ceil(std::max(a.x, b.x) + r));
    const int y0 = int(std::floor(std::min(a.y, b.y) - r)), y1 = int(std::ceil(std::max(a.y, b.y) + r));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5 - a.x, py = y + 0.5 - a.y;
        double t = len2 > 0 ? (px * dx + py * dy) / len2 : 0.0;
        t = std::clamp(t, 0.0, 1.0);
        if (dash > 0 && std::fmod(t * len, 2 * dash) > dash) continue;
        const double ex = px - t * dx, ey = py - t * dy;
        blend(x, y, c, width / 2 + 0.5 - std::sqrt(ex * ex + ey * ey));
      }
    }
  }

  enum class Marker { Circle, Triangle, Square, Diamond, Cross };

  void marker(Point p, Marker m, double size, Rgb c) {
    const int r = int(std::ceil(size)) + 2;
    for (int y = int(p.y) - r; y <= int(p.y) + r; ++y) {
      for (int x = int(p.x) - r; x <= int(p.x) + r; ++x) {
        const double dx = x + 0.5 - p.x, dy = y + 0.5 - p.y;
        double d = 0;  // signed distance-like value, negative inside
        switch (m) {
          case Marker::Circle: d = std::hypot(dx, dy) - size; break;
          case Marker::Square: d = std::max(std::abs(dx), std::abs(dy)) - 0.85 * size; break;
          case Marker::Diamond: d = (std::abs(dx) + std::abs(dy)) / std::sqrt(2.0) - 0.8 * size; break;
          case Marker::Triangle:  // pointing up: apex at y = -1.2 size, base at y = +0.6 size
            d = std::max(dy - 0.6 * size, std::abs(dx) * 0.866 - dy * 0.5 - 0.6 * size);
            break;
          case Marker::Cross: {
            const double a = std::abs(dx - dy) / std::sqrt(2.0), b = std::abs(dx + dy) / std::sqrt(2.0);
            d = std::max(std::min(a, b) - 1.4, std::max(std::abs(dx), std::abs(dy)) - size);
            break;
          }
        }
        blend(x, y, c, 0.5 - d);
      }
    }
  }

  /// Text with its top-left corner at (x, y); `scale` pixels per font pixel; unknown characters
  /// are drawn as a box.
  void text(int x, int y, const std::string& s, Rgb c, int scale = 2) {
    for (char ch : s) {
      const auto it = fontGlyphs().find(ch);
      for (int row = 0; row < 7; ++row) {
        for (int col = 0; col < 5; ++col) {
          const bool ink = it != fontGlyphs().end() ? it->second[row * 5 + col] == '1'
                                                    : (row == 0 || row == 6 || col == 0 || col == 4);
          if (ink) fillRect(x + col * scale, y + row * scale, x + (col + 1) * scale, y + (row + 1) * scale, c);
        }
      }
      x += 6 * scale;
    }
  }
  static int textWidth(const std::string& s, int scale = 2) { return s.empty() ? 0 : int(s.size()) * 6 * scale - scale; }

 private:
  RgbImage image_;
};

struct SolverStyle {
  Rgb color;
  Canvas::Marker marker;
};

SolverStyle styleOf(const std::string& solver) {
  switch (solverRank(solver)) {
    case 0: return {{40, 40, 40}, Canvas::Marker::Circle};
    case 1: return {{110, 170, 230}, Canvas::Marker::Triangle};
    case 2: return {{30, 80, 200}, Canvas::Marker::Square};
    case 3: return {{240, 160, 40}, Canvas::Marker::Diamond};
    case 4: return {{210, 30, 30}, Canvas::Marker::Cross};
    default: return {{120, 120, 120}, Canvas::Marker::Circle};
  }
}

std::string decadeLabel(int e, const std::string& unit) {
  // unit "" (counts): 1K, 10K, 1M ...; "s": 0.01 s .. 1000 s, 1e4 s; "B": 10 MB, 1 GB ...
  if (unit == "B") {
    static const char* names[] = {"B", "kB", "MB", "GB", "TB"};
    if (e < 0 || e >= 15) return "1e" + std::to_string(e) + " B";
    const int k = e / 3;
    return std::string(e % 3 == 0 ? "1" : e % 3 == 1 ? "10" : "100") + " " + names[k];
  }
  if (unit == "s") {
    if (e < -3 || e > 4) return "1e" + std::to_string(e) + " s";
    if (e < 0) return "0." + std::string(std::size_t(-e - 1), '0') + "1 s";
    return "1" + std::string(std::size_t(e), '0') + " s";
  }
  static const char* suffix[] = {"", "K", "M", "G"};
  if (e < 0 || e >= 12) return "1e" + std::to_string(e);
  return std::string(e % 3 == 0 ? "1" : e % 3 == 1 ? "10" : "100") + suffix[e / 3];
}

struct Panel {
  int x0, y0, x1, y1;  // plot area in pixels
  int ex0, ex1, ey0, ey1;  // decades shown
  Point at(double x, double y) const {
    const double u = (std::log10(x) - ex0) / double(ex1 - ex0), v = (std::log10(y) - ey0) / double(ey1 - ey0);
    return {x0 + u * (x1 - x0), y1 - v * (y1 - y0)};
  }
};

/// Decades [floor(log10 min), ceil(log10 max)] of positive values, at least one decade wide.
std::pair<int, int> decadeRange(const std::vector<double>& values) {
  double lo = 1e300, hi = 0;
  for (double v : values) {
    if (v > 0 && std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (hi <= 0) return {0, 1};
  int a = int(std::floor(std::log10(lo) + 1e-9)), b = int(std::ceil(std::log10(hi) - 1e-9));
  if (b <= a) b = a + 1;
  return {a, b};
}

void drawPanel(Canvas& canvas, const Panel& p, const std::string& title, const std::string& yUnit,
               const std::vector<Run>& runs, double (*value)(const Run&), double limitLine) {
  const Rgb ink{30, 30, 30}, grid{225, 225, 225}, minor{242, 242, 242};
  // Grid: minor lines at 2..9 of each decade, major lines at decades.
  for (int axis = 0; axis < 2; ++axis) {
    const int e0 = axis == 0 ? p.ex0 : p.ey0, e1 = axis == 0 ? p.ex1 : p.ey1;
    for (int e = e0; e <= e1; ++e) {
      for (int m = 1; m <= 9 && (e < e1 || m == 1); ++m) {
        const double v = m * std::pow(10.0, e);
        const Point q = axis == 0 ? p.at(v, std::pow(10.0, p.ey0)) : p.at(std::pow(10.0, p.ex0), v);
        const Rgb col = m == 1 ? grid : minor;
        if (axis == 0) canvas.line({q.x, double(p.y0)}, {q.x, double(p.y1)}, 1.0, col);
        else canvas.line({double(p.x0), q.y}, {double(p.x1), q.y}, 1.0, col);
        const double tick = m == 1 ? 7 : 4;
        if (axis == 0) canvas.line({q.x, double(p.y1)}, {q.x, p.y1 + tick}, 1.0, ink);
        else canvas.line({p.x0 - tick, q.y}, {double(p.x0), q.y}, 1.0, ink);
        if (m != 1) continue;
        const std::string label = decadeLabel(e, axis == 0 ? "" : yUnit);
        if (axis == 0) canvas.text(int(q.x) - Canvas::textWidth(label) / 2, p.y1 + 12, label, ink);
        else canvas.text(p.x0 - 12 - Canvas::textWidth(label), int(q.y) - 7, label, ink);
      }
    }
  }
  canvas.line({double(p.x0), double(p.y0)}, {double(p.x0), double(p.y1)}, 1.5, ink);
  canvas.line({double(p.x0), double(p.y1)}, {double(p.x1), double(p.y1)}, 1.5, ink);
  canvas.text((p.x0 + p.x1 - Canvas::textWidth(title)) / 2, p.y0 - 26, title, ink);
  canvas.text((p.x0 + p.x1 - Canvas::textWidth("faces")) / 2, p.y1 + 34, "faces", ink);
  if (limitLine > 0) {
    const Point q = p.at(std::pow(10.0, p.ex0), limitLine);
    if (q.y >= p.y0 && q.y <= p.y1) {
      canvas.line({double(p.x0), q.y}, {double(p.x1), q.y}, 1.5, {200, 40, 40}, 6);
      const std::string label = "limit " + formatBytes(limitLine);
      canvas.text(p.x1 - Canvas::textWidth(label) - 6, int(q.y) - 20, label, {200, 40, 40});
    }
  }
  const std::vector<std::string> meshes = meshesOf(runs);
  for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
    for (const char* solver : kSolvers) {
      const Series s = seriesOf(runs, meshes[mi], solver, value);
      const SolverStyle style = styleOf(solver);
      for (std::size_t i = 0; i + 1 < s.size(); ++i) {
        canvas.line(p.at(s[i].first, s[i].second), p.at(s[i + 1].first, s[i + 1].second), 2.0, style.color,
                    mi == 0 ? 0.0 : 7.0);
      }
      for (const auto& [f, v] : s) canvas.marker(p.at(f, v), style.marker, 5.0, style.color);
    }
  }
}

RgbImage plotScaling(const std::vector<Run>& runs, double limitBytes) {
  const int panelW = 640, panelH = 500, legendH = 70;
  Canvas canvas(2 * panelW, panelH + legendH, {255, 255, 255});
  std::vector<double> faces, times, peaks;
  for (const Run& r : runs) {
    if (!r.ok()) continue;
    faces.push_back(r.faces());
    times.push_back(r.total());
    peaks.push_back(r.peak());
  }
  const auto [fx0, fx1] = decadeRange(faces);
  const auto [tx0, tx1] = decadeRange(times);
  auto [mx0, mx1] = decadeRange(peaks);
  if (limitBytes > 0 && !peaks.empty() && *std::max_element(peaks.begin(), peaks.end()) * 4 > limitBytes) {
    mx1 = std::max(mx1, int(std::ceil(std::log10(limitBytes))));
  }
  const Panel timePanel{100, 50, panelW - 25, panelH - 60, fx0, fx1, tx0, tx1};
  const Panel memPanel{panelW + 100, 50, 2 * panelW - 25, panelH - 60, fx0, fx1, mx0, mx1};
  drawPanel(canvas, timePanel, "total time of seamvox param", "s", runs, totalOf, 0.0);
  drawPanel(canvas, memPanel, "peak RSS", "B", runs, peakOf, limitBytes);
  // Legend: solvers (colour + marker), meshes (line style).
  const Rgb ink{30, 30, 30};
  int x = 60;
  const int y = panelH + 14;
  for (const char* solver : kSolvers) {
    if (std::none_of(runs.begin(), runs.end(), [&](const Run& r) { return r.solver == solver; })) continue;
    const SolverStyle style = styleOf(solver);
    canvas.line({double(x), y + 7.0}, {x + 36.0, y + 7.0}, 2.0, style.color);
    canvas.marker({x + 18.0, y + 7.0}, style.marker, 5.0, style.color);
    canvas.text(x + 44, y, solver, ink);
    x += 44 + Canvas::textWidth(solver) + 36;
  }
  const std::vector<std::string> meshes = meshesOf(runs);
  x = 60;
  for (std::size_t mi = 0; mi < meshes.size() && mi < 2; ++mi) {
    canvas.line({double(x), y + 37.0}, {x + 36.0, y + 37.0}, 2.0, ink, mi == 0 ? 0.0 : 7.0);
    canvas.text(x + 44, y + 30, meshes[mi], ink);
    x += 44 + Canvas::textWidth(meshes[mi]) + 36;
  }
  return canvas.image();
}

// ---------------------------------------------------------------------------------------------
// Self-check

int failures = 0;
void check(bool ok, const std::string& what) {
  if (!ok) {
    ++failures;
    std::fprintf(stderr, "self-check FAILED: %s\n", what.c_str());
  }
}

bool throwsInputError(const std::string& text) {
  try {
    parseFlatJson(text, "bad.json");
  } catch (const InputError&) {
    return true;
  }
  return false;
}

int selfCheck() {
  // The reader reads back what the project's writer writes.
  JsonWriter w;
  w.beginObject();
  w.key("faces").value(std::uint64_t(2304000)).key("name").value("a \"b\"\n\\c");
  w.key("seconds").beginObject().key("total").value(12.5e-3).key("round").value(-1.25e+7).endObject();
  w.key("list").beginArray().value(1).value(true).null().endArray();
  w.key("empty").beginObject().endObject();
  w.key("nan").value(std::nan(""));
  w.endObject();
  const FlatJson j = parseFlatJson(w.str(), "writer");
  check(j.at("faces").number == 2304000.0, "integer");
  check(j.at("name").text == "a \"b\"\n\\c", "escapes");
  check(j.at("seconds.total").number == 12.5e-3 && j.at("seconds.round").number == -1.25e7, "nested numbers");
  check(j.at("list.0").number == 1 && j.at("list.1").flag && j.at("list.2").type == JsonValue::Type::Null, "array");
  check(j.count("empty") == 0 && j.at("nan").type == JsonValue::Type::Null, "empty object, null");
  check(parseFlatJson(" {\"u\": \"\\u00e9\\u0041\"} ", "u").at("u").text == "\xc3\xa9" "A", "unicode escape");
  for (const char* bad : {"", "{", "{\"a\":}", "{\"a\" 1}", "{\"a\":1,}", "[1 2]", "{\"a\":01}", "{\"a\":1.}",
                          "{\"a\":-}", "{\"a\":\"x}", "{\"a\":tru}", "{} x", "{\"a\":\"\\q\"}", "{'a':1}"}) {
    check(throwsInputError(bad), std::string("malformed JSON rejected: ") + bad);
  }
  check(throwsInputError(std::string(100, '[') + std::string(100, ']')), "depth limit");
  try {
    parseFlatJson("{\n  \"a\": 1,\n  \"b\": x\n}", "r.json");
    check(false, "error position");
  } catch (const InputError& e) {
    check(std::string(e.what()).rfind("r.json:3:8:", 0) == 0, std::string("error position: ") + e.what());
  }
  // Run names.
  Run r;
  check(parseRunName("fertility_L3_voxloc128.json", r) && r.mesh == "fertility" && r.level == 3 &&
            r.solver == "voxloc128", "run name");
  check(parseRunName("my_mesh_L10_hat.json", r) && r.mesh == "my_mesh" && r.level == 10, "run name with _");
  check(!parseRunName("fertility_3_hat.json", r) && !parseRunName("x_L3_hat.txt", r) &&
            !parseRunName("_L3_hat.json", r) && !parseRunName("L3_hat.json", r), "bad run names");
  // CSV quoting.
  check(csvField("plain") == "plain" && csvField("a,b") == "\"a,b\"" && csvField("say \"x\"") == "\"say \"\"x\"\"\"",
        "csv quoting");
  // Crossover: t_hat = 1e-7 n^1.5, t_loc = 1e-3 n cross at n = (1e-3 / 1e-7)^2 = 1e8.
  Series hat, loc;
  for (double n = 1e4; n <= 1e9; n *= 4) {
    hat.emplace_back(n, 1e-7 * std::pow(n, 1.5));
    loc.emplace_back(n, 1e-3 * n);
  }
  const Crossover c = findCrossover(loc, hat);
  check(c.kind == Crossover::Kind::At && std::abs(c.faces / 1e8 - 1) < 1e-9, "crossover at 1e8: " + formatCount(c.faces));
  check(findCrossover(hat, loc).kind == Crossover::Kind::Below, "crossover below");
  const Series lateHat(hat.begin(), hat.begin() + 3);
  check(findCrossover(loc, lateHat).kind == Crossover::Kind::NotReached, "crossover not reached");
  check(findCrossover(loc, Series{}).kind == Crossover::Kind::None, "no common size");
  check(formatCount(2304000) == "2,304,000" && formatCount(999) == "999", "counts");
  check(roundSignificant(128677, 2) == 130000 && roundSignificant(0.0123, 2) == 0.012, "rounding");
  check(decadeLabel(4, "") == "10K" && decadeLabel(6, "") == "1M" && decadeLabel(-1, "s") == "0.1 s" &&
            decadeLabel(3, "s") == "1000 s" && decadeLabel(9, "B") == "1 GB" && decadeLabel(8, "B") == "100 MB",
        "decade labels");
  // Every character the plot writes has a glyph, and glyphs are 35 pixels.
  for (const auto& [ch, bits] : fontGlyphs()) check(std::strlen(bits) == 35, std::string("glyph ") + ch);
  for (const std::string& s : {std::string("total time of seamvox param peak RSS faces limit 20.00 GB hat vox64 vox128 "
                                           "voxloc64 voxloc128 fertility armadillo 0.01 s 100 MB 10K 1M kB")}) {
    for (char ch : s) check(fontHas(ch), std::string("font has '") + ch + "'");
  }
  // A synthetic study plots lines where the data are.
  std::vector<Run> runs;
  int level = 0;
  for (const auto& [n, t] : hat) {
    for (int s = 0; s < 2; ++s) {
      Run run;
      run.mesh = "synthetic";
      run.level = level;
      run.solver = s == 0 ? "hat" : "voxloc128";
      auto num = [](double v) {
        JsonValue x;
        x.type = JsonValue::Type::Number;
        x.number = v;
        return x;
      };
      run.json["faces"] = num(n);
      run.json["seconds.total"] = num(s == 0 ? t : 1e-3 * n);
      run.json["peakResidentBytes"] = num(s == 0 ? 1e3 * std::pow(n, 1.5) : 1e6 * n);
      runs.push_back(run);
    }
    ++level;
  }
  const RgbImage image = plotScaling(runs, 20e9);
  check(image.width == 1280 && image.height == 570, "image size");
  std::size_t red = 0, dark = 0;
  for (std::size_t i = 0; i < image.pixels.size(); i += 3) {
    const std::uint8_t* px = &image.pixels[i];
    if (px[0] == 210 && px[1] == 30 && px[2] == 30) ++red;
    if (px[0] == 40 && px[1] == 40 && px[2] == 40) ++dark;
  }
  check(red > 500 && dark > 500, "both series drawn (" + std::to_string(red) + ", " + std::to_string(dark) + " px)");
  const std::vector<std::string> summary = summarize(runs, 20);
  check(!summary.empty() && summary[0].find("faster from about 100,000,000 faces") != std::string::npos,
        "summary names the crossover: " + (summary.empty() ? std::string() : summary[0]));
  if (failures == 0) std::printf("bench_scaling_report self-check: all checks passed\n");
  return failures == 0 ? 0 : 1;
}

int usage() {
  std::fprintf(stderr,
               "usage: bench_scaling_report RUNS_DIR [--csv F] [--md F] [--png F] [--png-link L]\n"
               "                            [--limit-gb G] [--command TEXT]\n"
               "       bench_scaling_report --self-check\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  seamvox::rerunWithPreferredRuntime(argv);  // the kernels and threads the seamvox command runs with
  if (argc == 2 && std::string(argv[1]) == "--self-check") return selfCheck();
  if (argc < 2 || argv[1][0] == '-') return usage();
  const std::string dir = argv[1];
  std::string csvPath, mdPath, pngPath, pngLink, command;
  double limitGb = 20.0;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) return usage();
    const std::string v = argv[++i];
    if (a == "--csv") csvPath = v;
    else if (a == "--md") mdPath = v;
    else if (a == "--png") pngPath = v;
    else if (a == "--png-link") pngLink = v;
    else if (a == "--command") command = v;
    else if (a == "--limit-gb") limitGb = std::atof(v.c_str());
    else return usage();
  }
  try {
    const std::vector<Run> runs = loadRuns(dir);
    if (runs.empty()) throw InputError(dir + ": no run files (<mesh>_L<level>_<solver>.json)");
    const std::vector<std::string> summary = summarize(runs, limitGb);
    if (!csvPath.empty()) writeTextFile(csvPath, writeCsv(runs));
    if (!mdPath.empty()) writeTextFile(mdPath, writeMarkdown(runs, summary, pngLink, command));
    if (!pngPath.empty()) writePng(pngPath, plotScaling(runs, limitGb * 1e9));
    std::printf("%zu runs in %s\n", runs.size(), dir.c_str());
    for (const std::string& line : summary) std::printf("%s\n", line.c_str());
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_scaling_report: %s\n", e.what());
    return 1;
  }
  return 0;
}
