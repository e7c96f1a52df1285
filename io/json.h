#pragma once
/// A minimal JSON writer for reports (no parsing). Produces pretty-printed, valid JSON.
#include <cstdint>
#include <string>
#include <vector>

namespace seamvox {

/// Builds a JSON document incrementally:
///   JsonWriter j; j.beginObject(); j.key("faces").value(12); j.endObject(); j.str();
/// Non-finite numbers are written as null.
class JsonWriter {
 public:
  JsonWriter& beginObject();
  JsonWriter& endObject();
  JsonWriter& beginArray();
  JsonWriter& endArray();
  JsonWriter& key(const std::string& name);
  JsonWriter& value(const std::string& text);
  JsonWriter& value(const char* text) { return value(std::string(text)); }
  JsonWriter& value(double number);
  JsonWriter& value(std::int64_t number);
  JsonWriter& value(std::uint64_t number);
  JsonWriter& value(int number) { return value(static_cast<std::int64_t>(number)); }
  JsonWriter& value(unsigned number) { return value(static_cast<std::uint64_t>(number)); }
  JsonWriter& value(bool flag);
  JsonWriter& null();
  /// The document; all containers must be closed.
  std::string str() const;

 private:
  void separate();
  std::string out_;
  std::vector<bool> hasItem_;  // per open container
  bool afterKey_ = false;
};

/// Escapes a string for JSON (quotes included).
std::string jsonQuote(const std::string& text);

}  // namespace seamvox
