#pragma once
/// The JSON document of `seamvox check --json` (and the Python module's check): one writer for
/// every key.
#include <string>

namespace seamvox {

struct CheckResult;

/// The verdict as JSON; `mesh` names what was checked (a file, or "<arrays>").
std::string checkReportJson(const std::string& mesh, const CheckResult& result);

}  // namespace seamvox
