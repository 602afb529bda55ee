// The programs' command line: values bound, checks that refuse with exit 2
// and say which option and why, --help and --version with exit 0.
#include "apps/command_line.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace command_line_test {

using rtfuse::apps::CommandLine;

struct Outcome {
  std::optional<int> exit;
  std::string out, err;
};

Outcome parse(CommandLine& cli, std::vector<const char*> args) {
  args.insert(args.begin(), "prog");
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  Outcome o;
  o.exit = cli.parse(static_cast<int>(args.size()), args.data());
  o.out = testing::internal::GetCapturedStdout();
  o.err = testing::internal::GetCapturedStderr();
  return o;
}

TEST(CommandLine, BindsEveryKindOfValue) {
  CommandLine cli{"prog: test"};
  std::string name, left;
  double d = 0.0;
  int i = 0;
  std::uint64_t u = 0;
  std::vector<int> ids;
  std::vector<std::string> words;
  bool flag = false;
  cli.option("left", &left, "positional");
  cli.option("-n,--name", &name, "a string");
  cli.option("--d", &d, "a double");
  cli.option("--i", &i, "an int");
  cli.option("--u", &u, "a 64-bit count");
  cli.option("--id", &ids, "repeated");
  cli.option("--word", &words, "repeated");
  cli.flag("-q,--quiet", &flag, "a flag");
  const Outcome o = parse(cli, {"L.png", "-n", "x", "--d", "2.5", "--i", "-3", "--u", "17179869184", "--id", "1",
                                "--id", "127", "--word", "a", "--word", "b", "-q"});
  EXPECT_FALSE(o.exit.has_value()) << o.err;
  EXPECT_EQ(left, "L.png");
  EXPECT_EQ(name, "x");
  EXPECT_EQ(d, 2.5);
  EXPECT_EQ(i, -3);
  EXPECT_EQ(u, std::uint64_t{1} << 34);
  EXPECT_EQ(ids, (std::vector<int>{1, 127}));
  EXPECT_EQ(words, (std::vector<std::string>{"a", "b"}));
  EXPECT_TRUE(flag);
}

TEST(CommandLine, AMissingRequiredOptionIsAUsageError) {
  CommandLine cli{"prog: test"};
  std::string map;
  cli.option("--map", &map, "the map").required();
  const Outcome o = parse(cli, {});
  EXPECT_EQ(o.exit, 2);
  EXPECT_NE(o.err.find("--map is required"), std::string::npos) << o.err;
}

TEST(CommandLine, ExcludedOptionsRefuseEachOtherInEitherOrder) {
  for (const bool config_first : {true, false}) {
    CommandLine cli{"prog: test"};
    std::string config, recording;
    auto c = cli.option("-c,--config", &config, "config");
    auto r = cli.option("-r,--recording", &recording, "recording");
    c.excludes(r);
    const Outcome o = config_first ? parse(cli, {"-c", "a", "-r", "b"}) : parse(cli, {"-r", "b", "-c", "a"});
    EXPECT_EQ(o.exit, 2);
    EXPECT_NE(o.err.find("excludes"), std::string::npos) << o.err;
  }
}

TEST(CommandLine, RangeRefusesValuesOutsideAndNonNumbersWithTheLimits) {
  for (const char* bad : {"0", "16777217", "nan", "x", "-inf"}) {
    CommandLine cli{"prog: test"};
    std::uint64_t mib = 4096;
    cli.option("--frame-memory", &mib, "MiB").range(1, 1 << 24);
    const Outcome o = parse(cli, {"--frame-memory", bad});
    EXPECT_EQ(o.exit, 2) << bad;
    EXPECT_NE(o.err.find("--frame-memory: must be a number in [1, 16777216], got '" + std::string(bad) + "'"),
              std::string::npos)
        << o.err;
    EXPECT_EQ(mib, 4096u) << bad;
  }
  CommandLine cli{"prog: test"};
  double r = -1.0;
  cli.option("--inflation", &r, "m").range(0.0, 10.0);
  EXPECT_FALSE(parse(cli, {"--inflation", "10"}).exit.has_value());
  EXPECT_EQ(r, 10.0);
}

TEST(CommandLine, NonNegativeRefusesNegativesAndInfinity) {
  for (const char* bad : {"-1", "inf", "nan", "soon"}) {
    CommandLine cli{"prog: test"};
    double duration = 0.0;
    cli.option("-d,--duration", &duration, "s").non_negative();
    const Outcome o = parse(cli, {"-d", bad});
    EXPECT_EQ(o.exit, 2) << bad;
    EXPECT_NE(o.err.find("must be a finite number >= 0, got '" + std::string(bad) + "'"), std::string::npos)
        << o.err;
  }
  CommandLine cli{"prog: test"};
  double duration = 1.0;
  cli.option("-d,--duration", &duration, "s").non_negative();
  EXPECT_FALSE(parse(cli, {"-d", "0"}).exit.has_value());
  EXPECT_EQ(duration, 0.0);
}

TEST(CommandLine, OneOfTakesOnlyItsChoices) {
  CommandLine cli{"prog: test"};
  std::string unknown = "closed";
  cli.option("--unknown", &unknown, "cells").one_of({"closed", "free"});
  EXPECT_EQ(parse(cli, {"--unknown", "maybe"}).exit, 2);
  EXPECT_EQ(unknown, "closed");
  CommandLine again{"prog: test"};
  again.option("--unknown", &unknown, "cells").one_of({"closed", "free"});
  EXPECT_FALSE(parse(again, {"--unknown", "free"}).exit.has_value());
  EXPECT_EQ(unknown, "free");
}

TEST(CommandLine, HelpAndVersionExitZeroAndPrintToStdout) {
  CommandLine cli{"prog: what it does"};
  int width = 4;
  cli.option("--width", &width, "position bytes").show_default();
  cli.version_flag("--version", "prog 1.2.3");
  const Outcome help = parse(cli, {"--help"});
  EXPECT_EQ(help.exit, 0);
  EXPECT_NE(help.out.find("prog: what it does"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--width INT=4"), std::string::npos) << help.out;
  CommandLine v{"prog"};
  v.version_flag("--version", "prog 1.2.3");
  const Outcome version = parse(v, {"--version"});
  EXPECT_EQ(version.exit, 0);
  EXPECT_NE(version.out.find("prog 1.2.3"), std::string::npos) << version.out;
}

TEST(CommandLine, AUsageErrorAfterParseIsExitTwoWithItsMessage) {
  CommandLine cli{"prog: test"};
  testing::internal::CaptureStderr();
  const int code = cli.usage_error("--cloud, --kitti or --bt is required");
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--cloud, --kitti or --bt is required"), std::string::npos) << err;
  EXPECT_NE(err.find("--help"), std::string::npos) << err;
}

}  // namespace command_line_test
