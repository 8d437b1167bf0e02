// A process's session id (random, never 0, 16 hex digits) and the lab name rule.
#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

#include "spindown/lab_name.hpp"
#include "spindown/session_id.hpp"

namespace spindown {
namespace {

TEST(SessionId, RandomNeverZeroAndPrintedAsSixteenHexDigits) {
  std::set<std::uint64_t> ids;
  for (int i = 0; i < 1000; ++i) ids.insert(new_session_id());
  EXPECT_EQ(ids.size(), 1000u);
  EXPECT_EQ(ids.count(0), 0u);
  EXPECT_EQ(session_text(0x3f9a0c1d5e7b2a48ull), "3f9a0c1d5e7b2a48");
  EXPECT_EQ(session_text(1), "0000000000000001");
  EXPECT_EQ(source_text("pc-1", 0xab), "host pc-1 (session 00000000000000ab)");
  EXPECT_NE(source_text("", 0).find("an unnamed source"), std::string::npos);
  // A hostile host name is printed safely: cut, control characters and non-UTF-8 escaped.
  std::string hostile = "evil\nline\x01\xff";
  hostile.append(100, 'x');
  const std::string shown = shown_name(hostile);
  EXPECT_EQ(shown.find('\n'), std::string::npos);
  EXPECT_NE(shown.find("\\xff"), std::string::npos);
  EXPECT_LT(shown.size(), 80u);
}

TEST(LabName, OptionElseEnvironmentElseLab) {
  EXPECT_EQ(choose_lab_name("", std::nullopt), "lab");
  EXPECT_EQ(choose_lab_name("", std::string("physics-1")), "physics-1");
  EXPECT_EQ(choose_lab_name("b_2", std::string("physics-1")), "b_2");
  EXPECT_EQ(choose_lab_name("", std::string("")), "lab");
  EXPECT_THROW(choose_lab_name("two words", std::nullopt), std::invalid_argument);
  try {
    choose_lab_name("", std::string("lab/1"));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SPINDOWN_LAB 'lab/1': lab name has character 0x2f"), std::string::npos)
        << e.what();
  }
  std::string why;
  EXPECT_FALSE(is_valid_lab_name(std::string(33, 'a'), &why));
  EXPECT_NE(why.find("lab name is 33 characters long"), std::string::npos) << why;
}

}  // namespace
}  // namespace spindown
