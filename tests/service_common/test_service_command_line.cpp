// services/common: the lab's connection options, taken the same way by every service (issue 42).
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "service_command_line.hpp"

using spindown::service::LabConnectionOptions;

namespace {

std::optional<spindown::service::LabConnection> resolve(std::vector<std::string> args, bool receives,
                                                        std::string* why) {
  CLI::App app{"test"};
  LabConnectionOptions o;
  o.add_to(app, receives);
  std::vector<const char*> argv{"test"};
  for (const auto& a : args) argv.push_back(a.c_str());
  if (const auto rc = spindown::service::parse(app, int(argv.size()), const_cast<char**>(argv.data()))) {
    *why = "exit " + std::to_string(*rc);
    return std::nullopt;
  }
  return o.resolve(why);
}

}  // namespace

TEST(ServiceCommandLine, AReceiverGetsItsBufferAndTheGateTheLabsName) {
  std::string why;
  const auto c = resolve({"--lcm-url", "udpm://239.255.76.68:7668?ttl=0", "--lab", "physics-1"}, true, &why);
  ASSERT_TRUE(c) << why;
  EXPECT_NE(c->lcm_url.find("recv_buf_size="), std::string::npos) << c->lcm_url;
  EXPECT_EQ(c->lab.lab, "physics-1");
  EXPECT_EQ(c->gate().lab, "physics-1");
  EXPECT_EQ(c->gate().sent_to, "239.255.76.68:7668");  // the gate judges the group it listens on
}

TEST(ServiceCommandLine, ASenderKeepsTheUrlAsGivenAndHasNoRecvBufOption) {
  std::string why;
  const auto c = resolve({"--lcm-url", "udpm://239.255.76.68:7668?ttl=0"}, false, &why);
  ASSERT_TRUE(c) << why;
  EXPECT_EQ(c->lcm_url, "udpm://239.255.76.68:7668?ttl=0");
  EXPECT_FALSE(resolve({"--recv-buf", "1000"}, false, &why));
  EXPECT_EQ(why, "exit 2");
}

TEST(ServiceCommandLine, ABadLabNameOrMissingKeyIsSaid) {
  std::string why;
  EXPECT_FALSE(resolve({"--lab", "bad lab"}, true, &why));
  EXPECT_NE(why.find("--lab"), std::string::npos) << why;
  EXPECT_FALSE(resolve({"--key", "/nonexistent/lab.key"}, true, &why));
  EXPECT_NE(why.find("/nonexistent/lab.key"), std::string::npos) << why;
}
