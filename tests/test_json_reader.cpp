// The JSON reader reads back what the writer writes, rejects malformed text with a position, and
// finds values by dotted path.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/system/errors.h"
#include "io/json.h"
#include "io/json_reader.h"

namespace seamvox {
namespace {

TEST(JsonReader, ReadsBackWhatTheWriterWrites) {
  JsonWriter w;
  w.beginObject();
  w.key("faces").value(std::uint64_t(2304000)).key("name").value("a \"b\"\n\\c\t/");
  w.key("seconds").beginObject().key("total").value(12.5e-3).key("round").value(-1.25e+7).endObject();
  w.key("list").beginArray().value(1).value(true).null().value(false).endArray();
  w.key("empty").beginObject().endObject();
  w.key("nan").value(std::nan(""));
  w.endObject();
  const JsonValue j = parseJson(w.str());
  EXPECT_EQ(j.numberAt("faces"), 2304000.0);
  EXPECT_EQ(j["name"].text, "a \"b\"\n\\c\t/");
  EXPECT_EQ(j.numberAt("seconds.total"), 12.5e-3);
  EXPECT_EQ(j.numberAt("seconds.round"), -1.25e7);
  EXPECT_EQ(j.numberAt("list.0"), 1.0);
  EXPECT_EQ(j.numberAt("list.1"), 1.0);  // true reads as 1
  EXPECT_EQ(j.find("list.2")->type, JsonValue::Type::Null);
  EXPECT_EQ(j.numberAt("list.3"), 0.0);
  EXPECT_TRUE(std::isnan(j.numberAt("list.4")));
  EXPECT_TRUE(std::isnan(j.numberAt("nan")));
  EXPECT_EQ(j.find("empty")->type, JsonValue::Type::Object);
  EXPECT_EQ(j.find("seconds.missing"), nullptr);
  EXPECT_EQ(j.find("faces.x"), nullptr);
  EXPECT_THROW(j["missing"], InputError);
  const auto flat = flattenJson(j);
  EXPECT_EQ(flat.at("seconds.total").number, 12.5e-3);
  EXPECT_EQ(flat.count("empty"), 0u);
}

TEST(JsonReader, DecodesUnicodeEscapesAndSurrogatePairs) {
  EXPECT_EQ(parseJson(R"({"u": "\u00e9\u0041\ud83d\ude00"})").textAt("u"), "\xc3\xa9" "A\xf0\x9f\x98\x80");
  EXPECT_THROW(parseJson(R"(["\ud83d"x])"), InputError);
  EXPECT_THROW(parseJson(R"(["\ud83d\u0041"])"), InputError);
}

TEST(JsonReader, RejectsMalformedTextNamingSourceLineAndColumn) {
  for (const char* bad : {"", "{", "{\"a\":}", "{\"a\" 1}", "{\"a\":1,}", "[1 2]", "{\"a\":01}", "{\"a\":1.}",
                          "{\"a\":-}", "{\"a\":\"x}", "{\"a\":tru}", "{} x", "{\"a\":\"\\q\"}", "{'a':1}",
                          "[\"\x01\"]", "[1e]", "nul"}) {
    EXPECT_THROW(parseJson(bad), InputError) << bad;
  }
  EXPECT_THROW(parseJson(std::string(100, '[') + std::string(100, ']')), InputError);
  EXPECT_NO_THROW(parseJson(std::string(60, '[') + std::string(60, ']')));
  try {
    parseJson("{\n  \"a\": 1,\n  \"b\": x\n}", "r.json");
    FAIL() << "accepted a bad value";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("r.json:3:8:", 0), 0u) << e.what();
  }
}

TEST(JsonReader, RandomMutantsEitherParseOrThrowInputError) {
  JsonWriter w;
  w.beginObject().key("a").beginArray().value(1.5).value("x\"y").endArray();
  w.key("b").beginObject().key("c").value(true).endObject().endObject();
  const std::string text = w.str();
  std::mt19937 rng(7);
  for (int i = 0; i < 2000; ++i) {
    std::string m = text;
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = rng() % m.size();
      if (rng() % 2) m[at] = static_cast<char>(rng() % 256);
      else m.erase(at, 1 + rng() % 4);
      if (m.empty()) break;
    }
    try {
      parseJson(m, "mutant");
    } catch (const InputError&) {
    }
  }
}

}  // namespace
}  // namespace seamvox
