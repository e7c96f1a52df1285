#include "io/json.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace seamvox {

namespace {

/// Length of the well-formed UTF-8 sequence starting at s[i] (RFC 3629: no overlong forms, no
/// surrogates, nothing above U+10FFFF), or 0 when the byte there does not start one.
std::size_t utf8Length(const std::string& s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0u; };
  const unsigned b0 = byte(i);
  const auto continuation = [&](std::size_t k) { return (byte(k) & 0xC0u) == 0x80u; };
  if (b0 < 0x80) return 1;
  if (b0 >= 0xC2 && b0 <= 0xDF) return continuation(i + 1) ? 2 : 0;
  if (b0 >= 0xE0 && b0 <= 0xEF) {
    const unsigned b1 = byte(i + 1);
    const bool ok = (b0 == 0xE0 ? b1 >= 0xA0 : b0 == 0xED ? b1 < 0xA0 : true);
    return ok && continuation(i + 1) && continuation(i + 2) ? 3 : 0;
  }
  if (b0 >= 0xF0 && b0 <= 0xF4) {
    const unsigned b1 = byte(i + 1);
    const bool ok = (b0 == 0xF0 ? b1 >= 0x90 : b0 == 0xF4 ? b1 < 0x90 : true);
    return ok && continuation(i + 1) && continuation(i + 2) && continuation(i + 3) ? 4 : 0;
  }
  return 0;
}

}  // namespace

std::string jsonQuote(const std::string& text) {
  std::string out = "\"";
  for (std::size_t i = 0; i < text.size();) {
    const unsigned char ch = static_cast<unsigned char>(text[i]);
    const std::size_t length = utf8Length(text, i);
    if (length > 1) {
      out.append(text, i, length);
      i += length;
      continue;
    }
    ++i;
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        // Control characters, DEL, and bytes outside valid UTF-8 (as \u00XX: their Latin-1 reading).
        if (ch < 0x20 || ch >= 0x7F) {
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
