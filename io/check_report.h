#pragma once
/// The JSON document of `seamvox check --json` (and the Python module's check): one writer for
/// every key.
#include <functional>
#include <string>

namespace seamvox {

struct CheckResult;
class JsonWriter;

/// The verdict as JSON; `mesh` names what was checked (a file, or "<arrays>"). `extra`, when
/// given, adds its keys at the end of the object (how the command measured it).
std::string checkReportJson(const std::string& mesh, const CheckResult& result,
                            const std::function<void(JsonWriter&)>& extra = {});

}  // namespace seamvox
