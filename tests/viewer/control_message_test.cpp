#include <gtest/gtest.h>

#include "sflsh/viewer/control_message.hpp"

namespace sflsh::viewer {
namespace {

TEST(ControlMessage, ToolPoseFieldsAsWritten) {
  const ControlParse p = parse_control_message(
      R"({"type":"tool","seq":42,"t":1.5,"tool":0,"pos":[0.1,-0.2,0.3],"quat":[0,1,0,0],"closure":0.25,"extra":1})");
  ASSERT_TRUE(p.message) << p.error;
  EXPECT_EQ(p.message->type, ControlType::kTool);
  EXPECT_EQ(p.message->seq, 42u);
  EXPECT_EQ(p.message->pose.time, 1.5);
  EXPECT_EQ(p.message->pose.position.x(), 0.1);
  EXPECT_EQ(p.message->pose.position.y(), -0.2);
  EXPECT_EQ(p.message->pose.position.z(), 0.3);
  EXPECT_EQ(p.message->pose.orientation.x(), 1.0);
  EXPECT_EQ(p.message->pose.orientation.w(), 0.0);
  EXPECT_EQ(p.message->pose.closure, 0.25);
}

TEST(ControlMessage, PanelMessages) {
  auto one = [](const char* text) {
    const ControlParse p = parse_control_message(text);
    EXPECT_TRUE(p.message) << text << ": " << p.error;
    return p.message.value_or(ControlMessage{});
  };
  EXPECT_TRUE(one(R"({"type":"pause","seq":1,"paused":true})").paused);
  EXPECT_FALSE(one(R"({"type":"pause","seq":1,"paused":false})").paused);
  EXPECT_EQ(one(R"({"type":"step","seq":2})").type, ControlType::kStep);
  EXPECT_EQ(one(R"({"type":"reset","seq":3})").type, ControlType::kReset);
  EXPECT_EQ(one(R"({"type":"stiffness","seq":4,"scale":2.5})").value, 2.5);
  EXPECT_EQ(one(R"({"type":"seek","seq":5,"time":0.75})").value, 0.75);
  EXPECT_EQ(one(R"({"type":"speed","seq":6,"speed":0.5})").value, 0.5);
}

TEST(ControlMessage, MalformedRejectedWithTheField) {
  const std::pair<const char*, const char*> cases[] = {
      {"", "not JSON"},
      {"{", "not JSON"},
      {"[1,2]", "JSON object"},
      {R"({"seq":1})", "\"type\""},
      {R"({"type":"fly","seq":1})", "unknown type"},
      {R"({"type":"pause"})", "\"seq\""},
      {R"({"type":"pause","seq":-1,"paused":true})", "\"seq\""},
      {R"({"type":"pause","seq":1.5,"paused":true})", "\"seq\""},
      {R"({"type":"pause","seq":1,"paused":1})", "\"paused\""},
      {R"({"type":"stiffness","seq":1,"scale":100})", "\"scale\""},
      {R"({"type":"stiffness","seq":1,"scale":"2"})", "\"scale\""},
      {R"({"type":"speed","seq":1,"speed":0})", "\"speed\""},
      {R"({"type":"seek","seq":1,"time":-2})", "\"time\""},
      {R"({"type":"tool","seq":1,"t":0,"pos":[0,0],"quat":[1,0,0,0],"closure":0})", "\"pos\""},
      {R"({"type":"tool","seq":1,"t":0,"pos":[0,0,"a"],"quat":[1,0,0,0],"closure":0})", "\"pos\""},
      {R"({"type":"tool","seq":1,"t":0,"pos":[0,0,1e9],"quat":[1,0,0,0],"closure":0})", "\"pos\""},
      {R"({"type":"tool","seq":1,"t":0,"pos":[0,0,0],"quat":[2,0,0,0],"closure":0})", "\"quat\""},
      {R"({"type":"tool","seq":1,"t":0,"pos":[0,0,0],"quat":[1,0,0,0],"closure":4})", "\"closure\""},
      {R"({"type":"tool","seq":1,"pos":[0,0,0],"quat":[1,0,0,0],"closure":0})", "\"t\""},
      {R"({"type":"tool","seq":1,"t":0,"tool":1.5,"pos":[0,0,0],"quat":[1,0,0,0],"closure":0})", "\"tool\""},
  };
  for (const auto& [text, fragment] : cases) {
    const ControlParse p = parse_control_message(text);
    EXPECT_FALSE(p.message) << text;
    EXPECT_NE(p.error.find(fragment), std::string::npos) << text << " -> " << p.error;
  }
  EXPECT_FALSE(parse_control_message(std::string(kMaxControlMessageBytes + 1, ' ')).message);
}

}  // namespace
}  // namespace sflsh::viewer
