#include <gtest/gtest.h>

#include <cmath>

#include "io/json.h"

using seamvox::findJsonNumber;
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

TEST(Json, NumbersAreFoundByTheirPathNotByTheFirstKeyOfThatName) {
  // As in a param report: refinement rounds carry "flipped" before the map's quality does.
  JsonWriter j;
  j.beginObject();
  j.key("note").value("\"flipped\": 7, {\"quality\": [");
  j.key("refine").beginObject().key("flipped").value(5);
  j.key("rounds").beginArray().beginObject().key("flipped").value(3).endObject().endArray();
  j.endObject();
  j.key("quality").beginObject();
  j.key("seamless").value(true).key("flipped").value(std::uint64_t{2}).key("error").value(-1.5e-3);
  j.endObject();
  j.key("faces").value(12).key("name").value("x");
  j.endObject();
  const std::string s = j.str();
  EXPECT_EQ(findJsonNumber(s, "quality.flipped"), 2.0);
  EXPECT_EQ(findJsonNumber(s, "refine.flipped"), 5.0);
  EXPECT_EQ(findJsonNumber(s, "quality.seamless"), 1.0);
  EXPECT_EQ(findJsonNumber(s, "quality.error"), -1.5e-3);
  EXPECT_EQ(findJsonNumber(s, "faces"), 12.0);
  EXPECT_EQ(findJsonNumber(s, "flipped"), std::nullopt) << "no top-level member of that name";
  EXPECT_EQ(findJsonNumber(s, "name"), std::nullopt) << "a string is not a number";
  EXPECT_EQ(findJsonNumber(s, "faces.count"), std::nullopt);
  EXPECT_EQ(findJsonNumber("[1, 2]", "faces"), std::nullopt);
  EXPECT_EQ(findJsonNumber(s.substr(0, s.size() / 2), "quality.flipped"), std::nullopt);
}
