// pseudohaptic-session's KWin source (session/kwin_cursor.hpp) against a stand-in KWin on a private
// session bus (tests/kwin_stand_in.hpp): loading and running the script, the positions it sends, unloading
// at the end, and a KWin that refuses, stays silent, is absent, or leaves and comes back.
#include <gtest/gtest.h>
#include <poll.h>
#include <systemd/sd-bus.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "session/kwin_cursor.hpp"
#include "tests/geometry_printers.hpp"
#include "tests/kwin_stand_in.hpp"
#include "tests/scratch_dir.hpp"

namespace ph::session {
namespace {

using namespace std::chrono_literals;
using namespace ph::kwin_stand_in;

// Runs the helper's side (as its poll loop does) until `done` or two seconds have passed.
template <typename Done>
bool wait_until(KWinCursor& cursor, Done done) {
  const auto deadline = Clock::now() + 2s;
  while (Clock::now() < deadline) {
    cursor.dispatch();
    if (done()) return true;
    const Watch w = cursor.watch();
    pollfd p{w.fd, w.events, 0};
    ::poll(&p, 1, w.timeout_ms < 0 ? 20 : std::min(w.timeout_ms, 20));
  }
  return false;
}
class KWinCursorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::optional<std::string> program = find_dbus_daemon();
    if (!program) GTEST_SKIP() << "dbus-daemon is not installed (Debian: dbus-daemon): no private session bus";
    bus_ = std::make_unique<PrivateBus>(*program, dir_.path());
    ASSERT_FALSE(bus_->address().empty()) << "dbus-daemon printed no address";
    std::filesystem::create_directories(scripts());
  }
  KWinOptions options(std::chrono::milliseconds first_position_timeout = 2s) const {
    KWinOptions o;
    o.bus_address = bus_->address();
    o.script_dir = scripts().string();
    o.first_position_timeout = first_position_timeout;
    return o;
  }
  std::filesystem::path scripts() const { return dir_ / "scripts"; }
  bool no_scripts_left() const { return std::filesystem::is_empty(scripts()); }
  const std::string& address() const { return bus_->address(); }

 private:
  ScratchDir dir_{"kwin"};
  std::unique_ptr<PrivateBus> bus_;
};

TEST(KWinScript, ReportsTheCursorToTheHelpersNameNowAndOnEveryMove) {
  const std::string script = kwin_cursor_script("org.pseudohaptic.Session.p4242");
  EXPECT_NE(script.find("workspace.cursorPosChanged.connect("), std::string::npos) << script;
  EXPECT_NE(script.find(R"(callDBus("org.pseudohaptic.Session.p4242", "/org/pseudohaptic/Session", )"
                        R"("org.pseudohaptic.Session", "Position", at.x, at.y))"),
            std::string::npos)
      << script;
  EXPECT_NE(script.find("workspace.cursorPos;"), std::string::npos) << script;
  EXPECT_NE(script.rfind("pseudohapticReport();"), script.find("pseudohapticReport()"));  // also sent at start
}

TEST(KWinScript, KdeSessionsAreTheOnesTheEnvironmentSaysAre) {
  EXPECT_TRUE(kde_session("6", ""));
  EXPECT_TRUE(kde_session("", "KDE"));
  EXPECT_TRUE(kde_session("", "ubuntu:kde"));
  EXPECT_FALSE(kde_session("", "GNOME"));
  EXPECT_FALSE(kde_session("", "KDEx:Hyprland"));
  EXPECT_FALSE(kde_session("", ""));
}

// KWin 6 sends its fractional position; KWin 5 whole pixels rounded half up, which the helper reports as
// the pixel centre that rounds to them (half a pixel up and left): `whole` maps what the script sends.
void loads_the_script_and_answers_with_the_latest_position(const std::string& address, const KWinOptions& options,
                                                           KWinVersion version, const std::string& run_object) {
  const double rounding = version == KWinVersion::five ? 0.5 : 0.0;
  const auto whole = [&](double x, double y) { return Vec2{x - rounding, y - rounding}; };
  StandInKWin kwin(address, {version, false, Sent{640, 360, "ii"}});
  ASSERT_TRUE(kwin.started());
  std::string why;
  const auto begin = Clock::now();
  std::unique_ptr<KWinCursor> cursor = KWinCursor::start(options, why);
  ASSERT_NE(cursor, nullptr) << why;
  EXPECT_LT(Clock::now() - begin, 1s);  // done when the first position came, not at the deadline
  EXPECT_EQ(cursor->name(), "kwin");
  EXPECT_EQ(cursor->position(), whole(640, 360));  // the script's report at start
  const std::string script_path = cursor->script_path();
  EXPECT_TRUE(std::filesystem::exists(script_path));
  Seen seen = kwin.seen();
  ASSERT_EQ(seen.loaded.size(), 1U);
  EXPECT_EQ(seen.loaded[0], std::make_pair(script_path, std::string(kKWinScriptPlugin)));
  EXPECT_EQ(seen.runs, std::vector<std::string>{run_object});
  EXPECT_NE(seen.script.find(cursor->bus_name()), std::string::npos) << seen.script;
  EXPECT_EQ(seen.unloaded, std::vector<std::string>{kKWinScriptPlugin});  // a stale one, before loading
  EXPECT_EQ(seen.calls.front(), "unloadScript");

  kwin.send({812.25, 95.5, "dd"});  // KWin 6: fractional pixels, as they come
  EXPECT_TRUE(wait_until(*cursor, [&] { return cursor->position() == Vec2{812.25, 95.5}; }));
  kwin.send({-1920, 4.75, "id"});
  EXPECT_TRUE(wait_until(*cursor, [&] { return cursor->position() == Vec2{-1920 - rounding, 4.75}; }));
  kwin.send({-7, 0, "ii"});
  kwin.send({100, 200, "ii"});  // two in a row: the latest wins
  EXPECT_TRUE(wait_until(*cursor, [&] { return cursor->position() == whole(100, 200); }));
  EXPECT_TRUE(wait_for_stand_in([&] { return kwin.seen().replies_ok == 5; }));  // each call answered
  EXPECT_EQ(kwin.seen().replies_error, 0) << kwin.seen().last_error;

  cursor.reset();  // the helper exits
  EXPECT_TRUE(wait_for_stand_in([&] { return kwin.seen().unloaded.size() == 2; }));
  seen = kwin.seen();
  EXPECT_EQ(seen.calls.back(), "unloadScript");
  EXPECT_EQ(seen.unloaded.back(), kKWinScriptPlugin);
  EXPECT_FALSE(std::filesystem::exists(script_path));
}

TEST_F(KWinCursorTest, Kwin6LoadsTheScriptAndAnswersWithTheLatestPosition) {
  loads_the_script_and_answers_with_the_latest_position(address(), options(), KWinVersion::six, "/Scripting/Script7");
}

TEST_F(KWinCursorTest, Kwin5LoadsTheScriptAndAnswersWithTheLatestPosition) {
  loads_the_script_and_answers_with_the_latest_position(address(), options(), KWinVersion::five, "/0");
}

TEST_F(KWinCursorTest, AKWinThatRefusesTheScriptGivesNoSource) {
  StandInKWin kwin(address(), {KWinVersion::six, true, Sent{1, 2, "ii"}});
  ASSERT_TRUE(kwin.started());
  std::string why;
  EXPECT_EQ(KWinCursor::start(options(), why), nullptr);
  EXPECT_NE(why.find("KWin did not load the script"), std::string::npos) << why;
  EXPECT_NE(why.find("scripting is disabled here"), std::string::npos) << why;
  EXPECT_TRUE(no_scripts_left());
}

TEST_F(KWinCursorTest, WithoutKWinOnTheBusThereIsNoSource) {
  std::string why;
  EXPECT_EQ(KWinCursor::start(options(), why), nullptr);
  EXPECT_NE(why.find("org.kde.KWin"), std::string::npos) << why;
  EXPECT_TRUE(no_scripts_left());
}

TEST_F(KWinCursorTest, AScriptThatSendsNothingIsUnloadedAndGivesNoSource) {
  StandInKWin kwin(address(), {KWinVersion::six, false, std::nullopt});
  ASSERT_TRUE(kwin.started());
  std::string why;
  const auto begin = Clock::now();
  EXPECT_EQ(KWinCursor::start(options(200ms), why), nullptr);
  EXPECT_LT(Clock::now() - begin, 1500ms);
  EXPECT_NE(why.find("sent no position within 200 ms"), std::string::npos) << why;
  EXPECT_EQ(kwin.seen().calls, (std::vector<std::string>{"unloadScript", "loadScript", "run", "unloadScript"}));
  EXPECT_TRUE(no_scripts_left());
}

TEST_F(KWinCursorTest, NoPositionYetIsNoAnswer) {
  StandInKWin kwin(address(), {KWinVersion::six, false, std::nullopt});
  ASSERT_TRUE(kwin.started());
  std::string why;
  std::unique_ptr<KWinCursor> cursor = KWinCursor::start(options(0ms), why);  // not waiting for the first
  ASSERT_NE(cursor, nullptr) << why;
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(cursor->position(), std::nullopt);
  kwin.send({3, 4, "ii"});
  EXPECT_TRUE(wait_until(*cursor, [&] { return cursor->position() == Vec2{3, 4}; }));
}

TEST_F(KWinCursorTest, OnlyKWinMayReportThePosition) {
  StandInKWin kwin(address(), {KWinVersion::six, false, Sent{10, 20, "ii"}});
  ASSERT_TRUE(kwin.started());
  std::string why;
  std::unique_ptr<KWinCursor> cursor = KWinCursor::start(options(), why);
  ASSERT_NE(cursor, nullptr) << why;
  const BusPtr other = connect_bus(address());
  ASSERT_NE(other, nullptr);
  // sd_bus_call would wait for the helper, which answers only when dispatched: send, then run both sides.
  sd_bus_message* raw = nullptr;
  ASSERT_GE(sd_bus_message_new_method_call(other.get(), &raw, cursor->bus_name().c_str(), kKWinCallbackPath,
                                           kKWinCallbackInterface, kKWinCallbackMethod),
            0);
  const MessagePtr call(raw);
  const double x = 1, y = 1;
  sd_bus_message_append(call.get(), "dd", x, y);
  std::optional<std::string> error;
  const auto on_reply = [](sd_bus_message* reply, void* data, sd_bus_error*) {
    const sd_bus_error* e = sd_bus_message_get_error(reply);
    *static_cast<std::optional<std::string>*>(data) = e != nullptr ? e->name : "none";
    return 0;
  };
  ASSERT_GE(sd_bus_call_async(other.get(), nullptr, call.get(), on_reply, &error, 0), 0);
  EXPECT_TRUE(wait_until(*cursor, [&] {
    while (sd_bus_process(other.get(), nullptr) > 0) {
    }
    return error.has_value();
  }));
  EXPECT_EQ(error, std::string(SD_BUS_ERROR_ACCESS_DENIED));
  EXPECT_EQ(cursor->position(), (Vec2{10, 20}));
}

TEST_F(KWinCursorTest, AKWinThatRestartsGetsTheScriptAgain) {
  auto first = std::make_unique<StandInKWin>(address(), StandInOptions{KWinVersion::six, false, Sent{5, 6, "ii"}});
  ASSERT_TRUE(first->started());
  std::string why;
  std::unique_ptr<KWinCursor> cursor = KWinCursor::start(options(), why);
  ASSERT_NE(cursor, nullptr) << why;
  first.reset();  // KWin leaves the bus: what it said last is no longer true
  EXPECT_TRUE(wait_until(*cursor, [&] { return !cursor->position(); }));
  StandInKWin second(address(), {KWinVersion::five, false, Sent{70, 80, "ii"}});
  ASSERT_TRUE(second.started());
  EXPECT_TRUE(wait_until(*cursor, [&] { return cursor->position() == Vec2{69.5, 79.5}; }));  // KWin 5's rounding
  EXPECT_EQ(second.seen().loaded.size(), 1U);
}

}  // namespace
}  // namespace ph::session
