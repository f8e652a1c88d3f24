#include "control_message.h"

#include <gtest/gtest.h>

#include <string>

namespace hapticut::servo {
namespace {

std::string refusal(const std::string& text) {
  try {
    (void)parse_control_message(text);
  } catch (const MalformedMessage& e) {
    return e.what();
  }
  return "";
}

std::string field_refusal(const std::string& text, const char* key) {
  const ControlMessage message = parse_control_message(text);
  try {
    (void)integer_field(message.body, key, 1, 65535);
  } catch (const CommandError& e) {
    return e.what();
  }
  return "";
}

TEST(ControlMessage, AByteOrderMarkAndAnEscapedNulAreRefused) {
  EXPECT_NE(refusal("\xEF\xBB\xBF"
                    R"({"type":"status"})")
                .find("byte order mark"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"type":"load","path":"a\u0000b"})").find("NUL"), std::string::npos);
  EXPECT_NE(refusal(R"({"type":"status","a\u0000":1})").find("NUL"), std::string::npos);
  EXPECT_NE(refusal(R"({"type":"set","x":[{"y":"\u0000"}]})").find("NUL"), std::string::npos);
  EXPECT_EQ(refusal(R"({"type":"status","id":"\u0041"})"), "");
}

TEST(ControlMessage, AnIntegerBelowItsMinimumIsRefused) {
  EXPECT_NE(field_refusal(R"({"type":"subscribe","port":0})", "port").find("out of range"),
            std::string::npos);
  EXPECT_NE(field_refusal(R"({"type":"subscribe","port":-1})", "port").find("out of range"),
            std::string::npos);
  EXPECT_EQ(field_refusal(R"({"type":"subscribe","port":1})", "port"), "");
}

TEST(ControlMessage, UnknownFieldsAreRefusedByName) {
  const ControlMessage message =
      parse_control_message(R"({"type":"subscribe","id":3,"port":5,"address":"10.0.0.1"})");
  try {
    refuse_unknown_fields(message.body, {"port", "rate_Hz"});
    FAIL() << "an unknown field was taken";
  } catch (const CommandError& e) {
    EXPECT_STREQ(e.what(), "unknown field 'address' (\"subscribe\" takes port, rate_Hz)");
  }
  EXPECT_NO_THROW(refuse_unknown_fields(message.body, {"port", "address"}));
}

TEST(ControlMessage, NestingIsBoundedAndNeverEchoed) {
  const std::string nested =
      R"({"type":"status","id":)" + std::string(100000, '[') + std::string(100000, ']') + "}";
  const std::string reason = refusal(nested);
  EXPECT_NE(reason.find("nested deeper than"), std::string::npos) << reason;
  EXPECT_LT(reason.size(), 200U);
}

TEST(ControlMessage, DuplicateKeysNulAndTrailingBytesAreRefused) {
  EXPECT_NE(refusal(R"({"type":"status","type":"shutdown"})").find("duplicate key"),
            std::string::npos);
  EXPECT_NE(refusal(std::string(R"({"type":"status"})") + '\0').find("NUL byte"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"type":"status"} {})").find("not valid JSON"), std::string::npos);
  EXPECT_NE(refusal(R"({"type":"status","id":[1]})").find("id: expected"), std::string::npos);
  EXPECT_NE(refusal(R"({"type":""})").find("type: expected"), std::string::npos);
  EXPECT_EQ(refusal(R"({"type":"status","id":"a"})"), "");
}

TEST(ControlMessage, ParseErrorsDoNotQuoteTheInput) {
  const std::string reason = refusal("12345abcdef");
  EXPECT_NE(reason.find("malformed JSON"), std::string::npos);
  EXPECT_EQ(reason.find("12345"), std::string::npos) << reason;
  EXPECT_EQ(reason.find("json.exception"), std::string::npos) << reason;
}

TEST(ControlMessage, IntegersAreIntegersWithinTheirRange) {
  EXPECT_EQ(field_refusal(R"({"type":"s","port":80})", "port"), "");
  for (const char* value : {"1.5", "true", "\"80\"", "18446744073709551616", "1e3"}) {
    const std::string reason =
        field_refusal(std::string(R"({"type":"s","port":)") + value + "}", "port");
    EXPECT_EQ(reason.rfind("port: expected an integer", 0), 0U) << value << ": " << reason;
  }
  EXPECT_EQ(field_refusal(R"({"type":"s","port":70000})", "port"),
            "port: out of range (1 to 65535)");
  EXPECT_EQ(field_refusal(R"({"type":"s","port":-1})", "port"), "port: out of range (1 to 65535)");
  EXPECT_EQ(field_refusal(R"({"type":"s"})", "port"), "port: missing");
}

TEST(ControlMessage, NumbersTakeTheEngineRange) {
  const ControlMessage message = parse_control_message(R"({"type":"set","ramp_time_s":1e308})");
  try {
    (void)number_field(message.body, "ramp_time_s", setting_range::kRampTime);
    FAIL() << "1e308 s taken as a ramp time";
  } catch (const CommandError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("ramp_time_s: must be <= 60", 0), 0U) << e.what();
  }
}

TEST(ControlMessage, ExcerptsAreShortAndPrintable) {
  EXPECT_EQ(quoted_excerpt("ab\n"), "'ab\\x0a'");
  const std::string long_text(1000, 'x');
  EXPECT_EQ(quoted_excerpt(long_text), "'" + std::string(kMaxEchoBytes, 'x') + "'...");
}

}  // namespace
}  // namespace hapticut::servo
