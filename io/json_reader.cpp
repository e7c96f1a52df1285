// A strict recursive-descent JSON reader (RFC 8259) for the project's reports.
#include "io/json_reader.h"

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "core/system/errors.h"

namespace seamvox {

namespace {

constexpr int kMaxDepth = 64;

class Parser {
 public:
  Parser(const std::string& text, const std::string& source) : s_(text), source_(source) {}

  JsonValue document() {
    JsonValue v = value(0);
    skipSpace();
    if (pos_ != s_.size()) fail("unexpected text after the document");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < pos_ && i < s_.size(); ++i) {
      column = s_[i] == '\n' ? 1 : column + 1;
      line += s_[i] == '\n';
    }
    throw InputError(source_ + ":" + std::to_string(line) + ":" + std::to_string(column) + ": JSON: " + what);
  }
  void skipSpace() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\n' || s_[pos_] == '\r' || s_[pos_] == '\t')) ++pos_;
  }
  void expect(char c) {
    skipSpace();
    if (pos_ >= s_.size() || s_[pos_] != c) fail(std::string("expected '") + c + "'");
    ++pos_;
  }
  bool consume(const char* word) {
    const std::size_t n = std::strlen(word);
    if (s_.compare(pos_, n, word) != 0) return false;
    pos_ += n;
    return true;
  }
  unsigned hex4() {
    if (pos_ + 4 > s_.size()) fail("short \\u escape");
    unsigned code = 0;
    for (int i = 0; i < 4; ++i) {
      const char c = s_[pos_++];
      code <<= 4;
      if (c >= '0' && c <= '9') code |= c - '0';
      else if (c >= 'a' && c <= 'f') code |= c - 'a' + 10;
      else if (c >= 'A' && c <= 'F') code |= c - 'A' + 10;
      else fail("bad hex digit in \\u escape");
    }
    return code;
  }
  static void appendUtf8(std::string& out, unsigned code) {
    if (code < 0x80) {
      out += static_cast<char>(code);
    } else if (code < 0x800) {
      out += static_cast<char>(0xC0 | (code >> 6));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else if (code < 0x10000) {
      out += static_cast<char>(0xE0 | (code >> 12));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (code >> 18));
      out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (code & 0x3F));
    }
  }
  unsigned escapedCodePoint() {
    unsigned code = hex4();
    if (code >= 0xD800 && code < 0xDC00 && s_.compare(pos_, 2, "\\u") == 0) {
      pos_ += 2;
      const unsigned low = hex4();
      if (low < 0xDC00 || low >= 0xE000) fail("unpaired surrogate in \\u escape");
      code = 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
    }
    return code;
  }
  std::string string() {
    expect('"');
    std::string out;
    for (;;) {
      if (pos_ >= s_.size()) fail("unterminated string");
      const char c = s_[pos_++];
      if (c == '"') return out;
      if (static_cast<unsigned char>(c) < 0x20) fail("control character in a string");
      if (c != '\\') {
        out += c;
        continue;
      }
      if (pos_ >= s_.size()) fail("unterminated escape");
      const char e = s_[pos_++];
      switch (e) {
        case '"': case '\\': case '/': out += e; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': appendUtf8(out, escapedCodePoint()); break;
        default: fail(std::string("bad escape \\") + e);
      }
    }
  }
  double number() {
    const std::size_t start = pos_;
    if (pos_ < s_.size() && s_[pos_] == '-') ++pos_;
    auto digits = [&] {
      const std::size_t from = pos_;
      while (pos_ < s_.size() && s_[pos_] >= '0' && s_[pos_] <= '9') ++pos_;
      return pos_ - from;
    };
    const std::size_t first = pos_;
    const std::size_t intDigits = digits();
    if (intDigits == 0) fail("bad value");
    if (intDigits > 1 && s_[first] == '0') fail("leading zero in a number");
    if (pos_ < s_.size() && s_[pos_] == '.') {
      ++pos_;
      if (digits() == 0) fail("bad number");
    }
    if (pos_ < s_.size() && (s_[pos_] == 'e' || s_[pos_] == 'E')) {
      ++pos_;
      if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) ++pos_;
      if (digits() == 0) fail("bad number");
    }
    return std::strtod(s_.substr(start, pos_ - start).c_str(), nullptr);
  }
  void members(JsonValue& v, int depth) {
    v.type = JsonValue::Type::Object;
    skipSpace();
    if (pos_ < s_.size() && s_[pos_] == '}') {
      ++pos_;
      return;
    }
    for (;;) {
      std::string key = string();
      expect(':');
      v.members[key] = value(depth + 1);
      skipSpace();
      if (pos_ < s_.size() && s_[pos_] == ',') {
        ++pos_;
        skipSpace();
        continue;
      }
      expect('}');
      return;
    }
  }
  void items(JsonValue& v, int depth) {
    v.type = JsonValue::Type::Array;
    skipSpace();
    if (pos_ < s_.size() && s_[pos_] == ']') {
      ++pos_;
      return;
    }
    for (;;) {
      v.items.push_back(value(depth + 1));
      skipSpace();
      if (pos_ < s_.size() && s_[pos_] == ',') {
        ++pos_;
        continue;
      }
      expect(']');
      return;
    }
  }
  JsonValue value(int depth) {
    if (depth > kMaxDepth) fail("nesting deeper than " + std::to_string(kMaxDepth));
    skipSpace();
    if (pos_ >= s_.size()) fail("unexpected end");
    JsonValue v;
    const char c = s_[pos_];
    if (c == '{') {
      ++pos_;
      members(v, depth);
    } else if (c == '[') {
      ++pos_;
      items(v, depth);
    } else if (c == '"') {
      v.type = JsonValue::Type::String;
      v.text = string();
    } else if (consume("null")) {
    } else if (consume("true")) {
      v.type = JsonValue::Type::Bool;
      v.flag = true;
    } else if (consume("false")) {
      v.type = JsonValue::Type::Bool;
    } else {
      v.type = JsonValue::Type::Number;
      v.number = number();
    }
    return v;
  }

  const std::string& s_;
  const std::string& source_;
  std::size_t pos_ = 0;
};

void flattenInto(const JsonValue& v, const std::string& path, std::map<std::string, JsonValue>& out) {
  const std::string prefix = path.empty() ? "" : path + ".";
  if (v.type == JsonValue::Type::Object) {
    for (const auto& [key, member] : v.members) flattenInto(member, prefix + key, out);
  } else if (v.type == JsonValue::Type::Array) {
    for (std::size_t i = 0; i < v.items.size(); ++i) flattenInto(v.items[i], prefix + std::to_string(i), out);
  } else {
    out[path] = v;
  }
}

}  // namespace

const JsonValue& JsonValue::operator[](const std::string& key) const {
  const auto it = members.find(key);
  if (type != Type::Object || it == members.end()) throw InputError("JSON: no member \"" + key + "\"");
  return it->second;
}

const JsonValue* JsonValue::find(const std::string& path) const {
  const JsonValue* v = this;
  std::size_t start = 0;
  while (v && start <= path.size()) {
    const std::size_t dot = path.find('.', start);
    const std::string part = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (v->type == Type::Object) {
      const auto it = v->members.find(part);
      v = it == v->members.end() ? nullptr : &it->second;
    } else if (v->type == Type::Array) {
      char* end = nullptr;
      const unsigned long i = std::strtoul(part.c_str(), &end, 10);
      v = (!part.empty() && *end == '\0' && i < v->items.size()) ? &v->items[i] : nullptr;
    } else {
      v = nullptr;
    }
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return v;
}

double JsonValue::numberAt(const std::string& path) const {
  const JsonValue* v = find(path);
  if (v && v->type == Type::Number) return v->number;
  if (v && v->type == Type::Bool) return v->flag ? 1.0 : 0.0;
  return std::nan("");
}

std::string JsonValue::textAt(const std::string& path) const {
  const JsonValue* v = find(path);
  return v && v->type == Type::String ? v->text : std::string();
}

JsonValue parseJson(const std::string& text, const std::string& source) {
  return Parser(text, source).document();
}

std::map<std::string, JsonValue> flattenJson(const JsonValue& document) {
  std::map<std::string, JsonValue> out;
  flattenInto(document, "", out);
  return out;
}

}  // namespace seamvox
