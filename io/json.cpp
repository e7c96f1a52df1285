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

}  // namespace seamvox
