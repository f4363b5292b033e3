// Channel selection for the time series (io/channel_select.hpp).
#include <gtest/gtest.h>

#include <stdexcept>

#include "io/channel_select.hpp"

namespace {

std::vector<lash::ChannelInfo> channels() {
  std::vector<lash::ChannelInfo> c;
  for (const char* n : {"crank.phi", "slider.x", "slider.vx", "rod_slider.Fn", "rod_slider.F", "energy.balance"})
    c.push_back({n, "", ""});
  return c;
}

}  // namespace

TEST(ChannelSelect, SplitsCommaSeparatedPatterns) {
  EXPECT_EQ(lash::split_channel_patterns(" slider.* ,rod_slider.F,, "),
            (std::vector<std::string>{"slider.*", "rod_slider.F"}));
  EXPECT_TRUE(lash::split_channel_patterns("").empty());
}

TEST(ChannelSelect, GlobsInTheChannelsOrderEachOnce) {
  using V = std::vector<std::size_t>;
  EXPECT_EQ(lash::select_channels(channels(), {}), (V{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(lash::select_channels(channels(), {"rod_slider.F*", "slider.*"}), (V{1, 2, 3, 4}));
  EXPECT_EQ(lash::select_channels(channels(), {"*.x", "slider.x"}), (V{1}));
  EXPECT_EQ(lash::select_channels(channels(), {"rod_slider.F?"}), (V{3}));
  EXPECT_EQ(lash::select_channels(channels(), {"*"}).size(), 6u);
  EXPECT_TRUE(lash::select_channels(channels(), {"time"}).empty());  // time alone
}

TEST(ChannelSelect, PatternMatchingNothingNamesTheClosest) {
  try {
    lash::select_channels(channels(), {"slider.x", "slidr.v*"});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "channel pattern 'slidr.v*' matches no channel (names are case-sensitive); the "
                 "closest are: slider.x, "
                 "slider.vx, rod_slider.F");
  }
}

TEST(ChannelSelect, AnUnclosedSetIsSaidSoNotTakenForAName) {
  // fnmatch takes a '[' that no ']' closes as itself: '[a-' matched no channel and the message
  // offered the closest names, as for a misspelt one.
  for (const std::string p : {"slider.[xv", "[a-", "slider.[!]", "rod_slider.[]"}) {
    try {
      lash::select_channels(channels(), {p});
      ADD_FAILURE() << p << ": no error";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()),
                "channel pattern '" + p + "': a '[' opens a set of characters that no ']' closes");
    }
  }
  // Closed sets, a ']' first in a set among them, select as the shell does.
  using V = std::vector<std::size_t>;
  EXPECT_EQ(lash::select_channels(channels(), {"slider.[xv]*"}), (V{1, 2}));
  EXPECT_EQ(lash::select_channels(channels(), {"slider.[!x]*"}), (V{2}));
  EXPECT_EQ(lash::select_channels(channels(), {"rod_slider.[]F]*"}), (V{3, 4}));
}
