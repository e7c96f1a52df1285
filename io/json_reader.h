#pragma once
/// The one JSON reader of the project: reports written by io/json (param, jobs, bench) are read
/// back through it by jobs, bench and the tests. A whole document in memory (reports are small).
#include <map>
#include <string>
#include <vector>

namespace seamvox {

struct JsonValue {
  enum class Type { Null, Bool, Number, String, Array, Object } type = Type::Null;
  bool flag = false;
  double number = 0.0;
  std::string text;  ///< UTF-8, escapes decoded
  std::vector<JsonValue> items;
  std::map<std::string, JsonValue> members;

  bool isNumber() const { return type == Type::Number; }
  bool has(const std::string& key) const { return type == Type::Object && members.count(key); }
  /// Member of an object; throws InputError naming the key when absent.
  const JsonValue& operator[](const std::string& key) const;
  /// The value at a dotted path ("quality.flipped", "stages.0.name"), or nullptr.
  const JsonValue* find(const std::string& path) const;
  /// The number at a dotted path (a bool counts as 0/1), or NaN when absent or not a number.
  double numberAt(const std::string& path) const;
  /// The string at a dotted path, or "" when absent or not a string.
  std::string textAt(const std::string& path) const;
};

/// Parses a whole document. Throws InputError "source:line:column: JSON: what" at the first
/// error (syntax, trailing text, nesting deeper than 64).
JsonValue parseJson(const std::string& text, const std::string& source = "JSON text");

/// Every scalar of a document under its dotted path ("a.b", arrays "a.0"), for table drivers.
std::map<std::string, JsonValue> flattenJson(const JsonValue& document);

}  // namespace seamvox
