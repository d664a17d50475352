// The viewer end to end in headless Debian chromium, driven by puppeteer-core
// (apps/viewer/test/e2e.mjs): `sflsh run --realtime --serve` on the small box
// avatar with a probe; the page shows frames; a Shift-drag pushes the probe
// 20 mm down (5 mm into the box); the server's own summary (printed at exit) must
// report tool contact and a soft displacement that grew; the rendered image
// is not blank; then the panel's controls: the stiffness slider reaches the
// server, pause holds, step takes one solver step, reset goes back to t = 0
// (tool at its start, no displacement). And `sflsh view` plays a result
// file: the time advances, the result's tool reaches the page, and its
// contact's force arrow is drawn.
// Skips with a message when chromium, node or apps/viewer/node_modules is
// absent (scripts/setup.sh installs them).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <regex>

#include <nlohmann/json.hpp>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/viewer/web_assets.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace sflsh::viewer {
namespace {

/// A child process (sh -c cmd) whose stdout is read line by line.
class Child {
 public:
  explicit Child(const std::string& cmd) {
    int fd[2];
    if (pipe(fd) != 0) throw std::runtime_error("pipe");
    pid_ = fork();
    if (pid_ == 0) {
      dup2(fd[1], 1);
      close(fd[0]);
      close(fd[1]);
      execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fd[1]);
    out_ = fdopen(fd[0], "r");
  }
  ~Child() {
    stop();
    if (out_) fclose(out_);
  }
  /// Lines until one matches `re` (returns its first group) or EOF ("").
  std::string wait_for(const std::regex& re) {
    char buf[4096];
    while (fgets(buf, sizeof buf, out_)) {
      log_ += buf;
      std::cmatch m;
      if (std::regex_search(buf, m, re)) return m[1].str();
    }
    return "";
  }
  /// SIGTERM (a normal end for a live run), then the rest of its stdout.
  std::string stop() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      char buf[4096];
      while (fgets(buf, sizeof buf, out_)) log_ += buf;
      waitpid(pid_, nullptr, 0);
      pid_ = -1;
    }
    return log_;
  }

 private:
  pid_t pid_ = -1;
  FILE* out_ = nullptr;
  std::string log_;
};

std::string skip_reason() {
  const char* env = std::getenv("CHROMIUM");
  const std::string chromium = env ? env : "/usr/bin/chromium";
  if (!fs::exists(chromium)) return "chromium not found at " + chromium + " (Debian package chromium; scripts/setup.sh)";
  if (std::system("command -v node > /dev/null 2>&1") != 0) return "node not found";
  if (!fs::exists(sflsh::test::source_dir() + "/apps/viewer/node_modules/puppeteer-core"))
    return "apps/viewer/node_modules absent (scripts/setup.sh runs npm ci)";
  if (!web_assets_problem().empty()) return web_assets_problem();
  return "";
}

// The box avatar under a probe tool (sphere of `radius` m) following `keyframes` (YAML list);
// `seconds` of simulation.
std::string probe_scene(double seconds, double radius, const std::string& keyframes) {
  return "solver: {dt: 1/250, seconds: " + std::to_string(seconds) +
         ", gravity: [0, 0, 0]}\noutput: {fps: 50}\nbodies:\n  - {name: base, avatar: box.h5, bones: kinematic}\n"
         "tools:\n  - name: probe\n    shape: {type: sphere, radius: " +
         std::to_string(radius) + "}\n    keyframes: " + keyframes + "\n";
}

std::string e2e(const std::string& url, const std::string& args) {
  std::string out;
  sflsh::test::run_command("node " + sflsh::test::source_dir() + "/apps/viewer/test/e2e.mjs --url " + url + " " + args +
                               " 2>&1",
                           &out);
  return out;
}

/// The last line of `text` that parses as a JSON object (e2e.mjs prints one).
nlohmann::json last_json_line(const std::string& text) {
  nlohmann::json found;
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const nlohmann::json j = nlohmann::json::parse(text.substr(begin, end - begin), nullptr, false);
    if (j.is_object()) found = j;
    begin = end + 1;
  }
  return found;
}

double number_after(const std::string& text, const std::string& key) {
  const auto at = text.find(key);
  return at == std::string::npos ? -1 : std::atof(text.c_str() + at + key.size());
}

using BrowserE2E = sflsh::test::BoxAvatarScene;

TEST_F(BrowserE2E, DraggingTheProbeIntoTheFleshMakesContactAndDisplacement) {
  if (const std::string why = skip_reason(); !why.empty()) GTEST_SKIP() << why;
  const std::string scene = write_scene(probe_scene(600, 0.006, "[{time: 0.0, position: [0.0, 0.045, 0.0]}]"));
  Child server(sflsh::test::sflsh_binary() + " -q run " + scene + " --realtime --serve --port 0 --quiet-status 2>" +
               (dir_ / "run.err").string());
  const std::string url = server.wait_for(std::regex("serving (http://[^ ]+)"));
  ASSERT_FALSE(url.empty()) << server.stop();
  const std::string png = (dir_ / "live.png").string();
  const std::string out = e2e(url, "--mode live --drag 0,-0.02,0 --seconds 2 --controls 1 --screenshot " + png);
  const std::string summary = server.stop();
  std::printf("%s\n%s", out.c_str(), summary.c_str());
  EXPECT_NE(out.find("\"ok\":true"), std::string::npos) << out;
  EXPECT_NE(out.find("\"contact\":true"), std::string::npos) << out;
  // The server's own account: contact frames and a displacement of more than 1 mm.
  EXPECT_GT(number_after(summary, "tool contact in "), 0) << summary;
  EXPECT_GT(number_after(summary, "max |u| "), 1.0) << summary;
  EXPECT_GT(number_after(out, "\"max_u_mm_after\":"), number_after(out, "\"max_u_mm_before\":") + 1.0) << out;
  EXPECT_GT(fs::file_size(png), 10000u);
  // The controls, as the frames reported them.
  const nlohmann::json r = last_json_line(out);
  ASSERT_TRUE(r.contains("controls")) << out;
  const nlohmann::json& c = r["controls"];
  EXPECT_NEAR(c.value("stiffness", 0.0), std::sqrt(10.0), 1e-9);  // the slider at 0.5 (log10 scale)
  EXPECT_EQ(c.value("paused", false), true);
  EXPECT_EQ(c.value("held", false), true);
  EXPECT_EQ(c.value("step_count", 0), 1);
  EXPECT_NEAR(c.value("step_dt", 0.0), 1.0 / 250, 1e-9);
  EXPECT_EQ(c.value("resets", 0), 1);
  EXPECT_EQ(c.value("reset_t", -1.0), 0.0);
  EXPECT_EQ(c.value("reset_max_u_mm", -1.0), 0.0);
  ASSERT_EQ(c["reset_device"].size(), 3u);
  EXPECT_NEAR(double(c["reset_device"][1]), 0.045, 1e-9);  // the keyframe start, not the dragged pose
  EXPECT_NEAR(c.value("reset_stiffness", 0.0), std::sqrt(10.0), 1e-9);
  EXPECT_GT(c.value("resumed_t", 0.0), 0.0);
}

TEST_F(BrowserE2E, ViewPlaysAResultFile) {
  if (const std::string why = skip_reason(); !why.empty()) GTEST_SKIP() << why;
  const std::string scene = write_scene(
      probe_scene(0.4, 0.005, "[{time: 0.0, position: [0.0, 0.045, 0.0]}, {time: 0.3, position: [0.0, 0.025, 0.0]}]"));
  const std::string h5 = (dir_ / "r.h5").string();
  std::string out;
  ASSERT_EQ(sflsh::test::run_command(sflsh::test::sflsh_binary() + " -q run " + scene + " --quiet-status --out " + h5 +
                                         " 2>&1",
                                     &out),
            0)
      << out;
  Child server(sflsh::test::sflsh_binary() + " view " + h5 + " --port 0 --speed 0.25 2>/dev/null");
  const std::string url = server.wait_for(std::regex("serving (http://[^ ]+)"));
  ASSERT_FALSE(url.empty()) << server.stop();
  out = e2e(url, "--mode playback --seconds 1");
  server.stop();
  std::printf("%s", out.c_str());
  EXPECT_NE(out.find("\"ok\":true"), std::string::npos) << out;
  // Playing at speed 0.25 for 1 s moves the clock by about 0.25 s.
  EXPECT_GT(number_after(out, "\"t_after\":"), 0.1) << out;
  // The probe reaches the page: in every frame, and as a row of the tools panel.
  EXPECT_NE(out.find("\"tools_in_frame\":1"), std::string::npos) << out;
  EXPECT_NE(out.find("\"tool_rows\":1"), std::string::npos) << out;
  EXPECT_NE(out.find("\"tools_panel\":true"), std::string::npos) << out;
  // Its contact with the box (the probe ends 5 mm into it): a contact arrow in the last frame.
  const nlohmann::json r = last_json_line(out);
  EXPECT_EQ(r.value("contacts_in_scene", 0), 1) << out;
  EXPECT_EQ(r.value("contact_arrows", 0), 1) << out;
  ASSERT_TRUE(r.contains("contact_force") && r["contact_force"].is_array()) << out;
  EXPECT_LT(double(r["contact_force"][1]), 0.0) << out;  // the probe pushes the body down
}

}  // namespace
}  // namespace sflsh::viewer
