#include "io/json.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace seamvox {

std::string jsonQuote(const std::string& text) {
  std::string out = "\"";
  for (unsigned char ch : text) {
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (ch < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", ch);
          out += buf;
        } else {
          out += static_cast<char>(ch);
        }
    }
  }
  return out + "\"";
}

void JsonWriter::separate() {
  if (afterKey_) {
    afterKey_ = false;
    return;
  }
  if (!hasItem_.empty()) {
    if (hasItem_.back()) out_ += ",";
    hasItem_.back() = true;
    out_ += "\n" + std::string(2 * hasItem_.size(), ' ');
  }
}

JsonWriter& JsonWriter::beginObject() {
  separate();
  out_ += "{";
  hasItem_.push_back(false);
  return *this;
}

JsonWriter& JsonWriter::endObject() {
  const bool any = hasItem_.back();
  hasItem_.pop_back();
  if (any) out_ += "\n" + std::string(2 * hasItem_.size(), ' ');
  out_ += "}";
  return *this;
}

JsonWriter& JsonWriter::beginArray() {
  separate();
  out_ += "[";
  hasItem_.push_back(false);
  return *this;
}

JsonWriter& JsonWriter::endArray() {
  const bool any = hasItem_.back();
  hasItem_.pop_back();
  if (any) out_ += "\n" + std::string(2 * hasItem_.size(), ' ');
  out_ += "]";
  return *this;
}

JsonWriter& JsonWriter::key(const std::string& name) {
  separate();
  out_ += jsonQuote(name) + ": ";
  afterKey_ = true;
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& text) {
  separate();
  out_ += jsonQuote(text);
  return *this;
}

JsonWriter& JsonWriter::value(double number) {
  separate();
  if (!std::isfinite(number)) {
    out_ += "null";
    return *this;
  }
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, number);
  out_.append(buf, res.ptr);
  return *this;
}

JsonWriter& JsonWriter::value(std::int64_t number) {
  separate();
  out_ += std::to_string(number);
  return *this;
}

JsonWriter& JsonWriter::value(std::uint64_t number) {
  separate();
  out_ += std::to_string(number);
  return *this;
}

JsonWriter& JsonWriter::value(bool flag) {
  separate();
  out_ += flag ? "true" : "false";
  return *this;
}

JsonWriter& JsonWriter::null() {
  separate();
  out_ += "null";
  return *this;
}

std::string JsonWriter::str() const {
  if (!hasItem_.empty()) throw std::logic_error("JsonWriter: unclosed container");
  return out_ + "\n";
}

namespace {

/// Index just past the JSON string that starts at text[at] == '"'.
std::size_t skipString(const std::string& text, std::size_t at) {
  for (++at; at < text.size(); ++at) {
    if (text[at] == '\\') {
      ++at;
    } else if (text[at] == '"') {
      return at + 1;
    }
  }
  return text.size();
}

std::size_t skipSpace(const std::string& text, std::size_t at) {
  while (at < text.size() && (text[at] == ' ' || text[at] == '\n' || text[at] == '\r' || text[at] == '\t')) ++at;
  return at;
}

/// Index of the value of member key in the object whose '{' is at text[open], or npos. Only
/// the object's own members count, not those of objects nested in it.
std::size_t findMember(const std::string& text, std::size_t open, const std::string& key) {
  const std::string quoted = jsonQuote(key);
  int depth = 0;
  for (std::size_t at = open; at < text.size();) {
    const char c = text[at];
    if (c == '"') {
      const std::size_t end = skipString(text, at);
      const std::size_t colon = skipSpace(text, end);
      if (depth == 1 && colon < text.size() && text[colon] == ':' &&
          text.compare(at, end - at, quoted) == 0) {
        return skipSpace(text, colon + 1);
      }
      at = end;
      continue;
    }
    if (c == '{' || c == '[') ++depth;
    if ((c == '}' || c == ']') && --depth == 0) break;
    ++at;
  }
  return std::string::npos;
}

}  // namespace

std::optional<double> findJsonNumber(const std::string& json, const std::string& dottedPath) {
  std::size_t value = skipSpace(json, 0);
  std::size_t start = 0;
  for (;;) {
    if (value >= json.size() || json[value] != '{') return std::nullopt;
    const std::size_t dot = dottedPath.find('.', start);
    value = findMember(json, value, dottedPath.substr(start, dot == std::string::npos ? dot : dot - start));
    if (value == std::string::npos) return std::nullopt;
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  if (json.compare(value, 4, "true") == 0) return 1.0;
  if (json.compare(value, 5, "false") == 0) return 0.0;
  double number = 0.0;
  const auto [end, error] = std::from_chars(json.data() + value, json.data() + json.size(), number);
  if (error != std::errc() || end == json.data() + value) return std::nullopt;
  return number;
}

}  // namespace seamvox
