#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "io/json.h"

using seamvox::JsonWriter;

TEST(Json, NestedDocumentIsValidAndEscaped) {
  JsonWriter j;
  j.beginObject();
  j.key("name").value("a \"quoted\"\nline");
  j.key("count").value(std::uint64_t{20000000});
  j.key("nan").value(std::nan(""));
  j.key("list").beginArray().value(1).value(2.5).endArray();
  j.key("empty").beginObject().endObject();
  j.endObject();
  const std::string s = j.str();
  EXPECT_NE(s.find("\"a \\\"quoted\\\"\\nline\""), std::string::npos);
  EXPECT_NE(s.find("20000000"), std::string::npos);
  EXPECT_NE(s.find("\"nan\": null"), std::string::npos);
  EXPECT_NE(s.find("2.5"), std::string::npos);
  EXPECT_NE(s.find("\"empty\": {}"), std::string::npos);
}

TEST(Json, UnclosedContainerIsAnError) {
  JsonWriter j;
  j.beginArray();
  EXPECT_THROW(j.str(), std::logic_error);
}

// --- any bytes give valid JSON ------------------------------------------------------------------

/// Decodes one UTF-8 code point at s[i] strictly (shortest form, no surrogates, at most
/// U+10FFFF); returns false for anything else.
bool decodeUtf8(const std::string& s, std::size_t& i, std::uint32_t& cp) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned lead = b(i);
  int extra = lead < 0x80 ? 0 : (lead >> 5) == 6 ? 1 : (lead >> 4) == 14 ? 2 : (lead >> 3) == 30 ? 3 : -1;
  if (extra < 0 || i + extra >= s.size()) return false;
  cp = extra == 0 ? lead : lead & (0x3F >> extra);
  for (int k = 1; k <= extra; ++k) {
    if ((b(i + k) & 0xC0) != 0x80) return false;
    cp = (cp << 6) | (b(i + k) & 0x3F);
  }
  static const std::uint32_t kMin[] = {0, 0x80, 0x800, 0x10000};
  if (cp < kMin[extra] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
  i += extra + 1;
  return true;
}

std::string encodeUtf8(std::uint32_t cp) {
  std::string out;
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
  return out;
}

/// A strict validator for the documents JsonWriter makes (objects, arrays, strings, numbers,
/// literals): the text must be UTF-8 and every string well formed. Collects decoded strings.
class JsonValidator {
 public:
  explicit JsonValidator(const std::string& text) : s_(text) {}
  bool valid(std::vector<std::string>& strings) {
    for (std::size_t i = 0; i < s_.size();) {
      std::uint32_t cp;
      if (!decodeUtf8(s_, i, cp)) return fail("not UTF-8");
    }
    strings_ = &strings;
    if (!value()) return false;
    space();
    return pos_ == s_.size() || fail("trailing text");
  }
  std::string error;

 private:
  bool fail(const std::string& what) {
    error = what + " at " + std::to_string(pos_);
    return false;
  }
  void space() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\n' || s_[pos_] == '\t' || s_[pos_] == '\r')) ++pos_;
  }
  bool literal(const char* word) {
    const std::size_t n = std::strlen(word);
    if (s_.compare(pos_, n, word) != 0) return false;
    pos_ += n;
    return true;
  }
  bool string() {
    if (pos_ >= s_.size() || s_[pos_] != '"') return fail("expected a string");
    ++pos_;
    std::string decoded;
    for (;;) {
      if (pos_ >= s_.size()) return fail("unterminated string");
      const unsigned char c = static_cast<unsigned char>(s_[pos_]);
      if (c == '"') break;
      if (c < 0x20) return fail("raw control character");
      if (c != '\\') {
        decoded += static_cast<char>(c);
        ++pos_;
        continue;
      }
      if (++pos_ >= s_.size()) return fail("cut escape");
      const char e = s_[pos_++];
      const char* simple = std::strchr("\"\\/bfnrt", e);
      if (e != 'u' && (!simple || !e)) return fail("bad escape");
      if (e != 'u') {
        decoded += std::string("\"\\/\b\f\n\r\t")[static_cast<std::size_t>(simple - "\"\\/bfnrt")];
        continue;
      }
      if (pos_ + 4 > s_.size()) return fail("cut \\u escape");
      std::uint32_t cp = 0;
      for (int k = 0; k < 4; ++k) {
        const char h = s_[pos_++];
        if (!std::isxdigit(static_cast<unsigned char>(h))) return fail("bad \\u escape");
        cp = cp * 16 + static_cast<std::uint32_t>(std::isdigit(static_cast<unsigned char>(h)) ? h - '0' : (h | 0x20) - 'a' + 10);
      }
      if (cp >= 0xD800 && cp <= 0xDFFF) return fail("lone surrogate escape");
      decoded += encodeUtf8(cp);
    }
    ++pos_;
    strings_->push_back(decoded);
    return true;
  }
  bool value() {
    space();
    if (pos_ >= s_.size()) return fail("missing value");
    const char c = s_[pos_];
    if (c == '"') return string();
    if (c == '{' || c == '[') {
      const char close = c == '{' ? '}' : ']';
      ++pos_;
      space();
      if (pos_ < s_.size() && s_[pos_] == close) return ++pos_, true;
      for (;;) {
        space();
        if (c == '{') {
          if (!string()) return false;
          space();
          if (pos_ >= s_.size() || s_[pos_++] != ':') return fail("expected ':'");
        }
        if (!value()) return false;
        space();
        if (pos_ < s_.size() && s_[pos_] == ',') {
          ++pos_;
          continue;
        }
        if (pos_ < s_.size() && s_[pos_] == close) return ++pos_, true;
        return fail("expected ',' or a close");
      }
    }
    if (literal("null") || literal("true") || literal("false")) return true;
    const std::size_t start = pos_;
    if (pos_ < s_.size() && s_[pos_] == '-') ++pos_;
    while (pos_ < s_.size() && std::strchr("0123456789.eE+-", s_[pos_]) && s_[pos_]) ++pos_;
    return pos_ > start || fail("bad value");
  }

  const std::string& s_;
  std::size_t pos_ = 0;
  std::vector<std::string>* strings_ = nullptr;
};

bool isUtf8(const std::string& s) {
  std::uint32_t cp;
  for (std::size_t i = 0; i < s.size();) {
    if (!decodeUtf8(s, i, cp)) return false;
  }
  return true;
}

/// The expected reading of raw bytes: well-formed UTF-8 kept, every other byte as U+00XX.
std::string latin1Reading(const std::string& bytes) {
  std::string out;
  for (std::size_t i = 0; i < bytes.size();) {
    std::size_t j = i;
    std::uint32_t cp;
    if (decodeUtf8(bytes, j, cp)) {
      out.append(bytes, i, j - i);
      i = j;
    } else {
      out += encodeUtf8(static_cast<unsigned char>(bytes[i++]));
    }
  }
  return out;
}

TEST(Json, AnyBytesGiveValidUtf8Json) {
  std::mt19937 rng(5);
  const std::vector<std::string> pieces = {"\xC3\xA9", "\xE2\x82\xAC", "\xF0\x9F\x98\x80", "\xC3", "\xE2\x82",
                                           "\xED\xA0\x80", "\xC0\xAF", "\xF4\x90\x80\x80", "\xFF", "\x7F",
                                           "\"", "\\", "/", "\n", std::string(1, '\0'), "\x1F", "a", ".obj"};
  int invalid = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<std::string> inputs;
    for (int n = 0; n < 3; ++n) {
      std::string text;
      const int length = static_cast<int>(rng() % 24);
      for (int k = 0; k < length; ++k) {
        if (rng() % 2) text += static_cast<char>(rng() % 256);
        else text += pieces[rng() % pieces.size()];
      }
      invalid += !isUtf8(text);
      inputs.push_back(text);
    }
    JsonWriter j;
    j.beginObject();
    j.key(inputs[0]).value(inputs[1]);
    j.key("list").beginArray().value(inputs[2]).endArray();
    j.endObject();
    const std::string document = j.str();
    std::vector<std::string> strings;
    JsonValidator validator(document);
    ASSERT_TRUE(validator.valid(strings)) << validator.error << "\n" << document;
    ASSERT_EQ(strings.size(), 4u);
    EXPECT_EQ(strings[0], latin1Reading(inputs[0]));
    EXPECT_EQ(strings[1], latin1Reading(inputs[1]));
    EXPECT_EQ(strings[3], latin1Reading(inputs[2]));
    for (const int k : {0, 1}) {
      if (isUtf8(inputs[k])) EXPECT_EQ(strings[k == 0 ? 0 : 1], inputs[k]) << "valid text is kept as it is";
    }
  }
  EXPECT_GT(invalid, 1000) << "the trials must exercise invalid bytes";
  // A Latin-1 file name reads as itself.
  EXPECT_EQ(seamvox::jsonQuote("caf\xE9.obj"), "\"caf\\u00e9.obj\"");
  EXPECT_EQ(seamvox::jsonQuote("caf\xC3\xA9.obj"), "\"caf\xC3\xA9.obj\"");
}
