#include <gtest/gtest.h>

#include <cmath>

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
