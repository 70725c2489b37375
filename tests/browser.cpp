#include "browser.hpp"

#include <fcntl.h>
#include <png.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "test_support.hpp"

namespace chladni::test {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

// The pixels of a PNG whose header `img` has read, as RGBA.
Image finish_png(png_image& img, const std::string& what) {
  img.format = PNG_FORMAT_RGBA;
  Image out;
  out.width = int(img.width), out.height = int(img.height);
  out.rgba.resize(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, out.rgba.data(), 0, nullptr))
    throw std::runtime_error(what + ": cannot decode the PNG");
  return out;
}

}  // namespace

Browser::Browser(int width, int height) {
  const char* env = std::getenv("CHLADNI_CHROMIUM");
  const std::string exe = env && *env ? env : "/usr/bin/chromium";
  if (access(exe.c_str(), X_OK) != 0)
    throw std::runtime_error(exe + " not found: install Debian's chromium (scripts/deps.sh)");
  profile_ = temp_path("chromium_profile");
  std::filesystem::remove_all(profile_);
  int in[2], out[2];
  if (pipe(in) != 0 || pipe(out) != 0) throw std::runtime_error("pipe failed");
  const std::string size = "--window-size=" + std::to_string(width) + "," + std::to_string(height);
  const std::string profile = "--user-data-dir=" + profile_;
  const std::string log = temp_path("chromium.log");
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    // The browser reads commands on fd 3 and writes replies on fd 4.
    const int r = dup(in[0]), w = dup(out[1]);
    dup2(r, 3);
    dup2(w, 4);
    for (int fd = 5; fd < 1024; ++fd) close(fd);
    const int logfd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (logfd >= 0) dup2(logfd, 1), dup2(logfd, 2);
    unsetenv("LD_PRELOAD");  // the sanitizer build's runtime is not the browser's
    execl(exe.c_str(), exe.c_str(), "--headless", "--no-sandbox", "--remote-debugging-pipe",
          profile.c_str(), size.c_str(), "--no-first-run", "--no-default-browser-check",
          "--disable-extensions", "--disable-background-networking", "--disable-component-update",
          "--disable-dev-shm-usage", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
          "--hide-scrollbars", "--mute-audio", "--autoplay-policy=no-user-gesture-required",
          "about:blank", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(in[0]);
  close(out[1]);
  to_browser_ = in[1];
  from_browser_ = out[0];
  signal(SIGPIPE, SIG_IGN);
  try {
    attach();
  } catch (...) {
    shutdown();
    throw;
  }
}

void Browser::attach() {
  // Attach to the page the browser opened (flat sessions: one pipe for all).
  std::string target;
  const json targets = browser_call("Target.getTargets");
  for (const auto& t : targets["targetInfos"])
    if (t["type"] == "page") target = t["targetId"];
  if (target.empty())
    target = browser_call("Target.createTarget", {{"url", "about:blank"}})["targetId"];
  const json attached =
      browser_call("Target.attachToTarget", {{"targetId", target}, {"flatten", true}});
  session_ = attached["sessionId"];
  call("Page.enable");
  call("Runtime.enable");
  call("Log.enable");
}

Browser::~Browser() {
  shutdown();
}

void Browser::shutdown() {
  if (to_browser_ >= 0) close(to_browser_);
  if (from_browser_ >= 0) close(from_browser_);
  if (pid_ > 0) {
    kill(pid_, SIGTERM);
    bool reaped = false;
    for (int i = 0; i < 50 && !reaped; ++i) {
      reaped = waitpid(pid_, nullptr, WNOHANG) == pid_;
      if (!reaped) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (!reaped) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    pid_ = -1;
  }
  to_browser_ = from_browser_ = -1;
  std::error_code ec;
  std::filesystem::remove_all(profile_, ec);
}

void Browser::send(const json& message) {
  const std::string text = message.dump() + '\0';
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(to_browser_, text.data() + done, text.size() - done);
    if (n <= 0) throw std::runtime_error("the browser closed its pipe (see chromium.log)");
    done += std::size_t(n);
  }
}

json Browser::receive(double timeout_s) {
  const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const std::size_t nul = pending_.find('\0');
    if (nul != std::string::npos) {
      json m = json::parse(pending_.substr(0, nul));
      pending_.erase(0, nul + 1);
      return m;
    }
    const double left = std::chrono::duration<double>(end - Clock::now()).count();
    if (left <= 0) throw std::runtime_error("no message from the browser in time");
    pollfd p{from_browser_, POLLIN, 0};
    if (poll(&p, 1, int(left * 1000) + 1) <= 0) continue;
    char buf[1 << 16];
    const ssize_t n = read(from_browser_, buf, sizeof buf);
    if (n <= 0) throw std::runtime_error("the browser exited (see chromium.log)");
    pending_.append(buf, std::size_t(n));
  }
}

void Browser::note_event(const json& e) {
  const std::string method = e.value("method", "");
  const json& p = e.contains("params") ? e["params"] : json::object();
  if (method == "Runtime.exceptionThrown") {
    const json& d = p["exceptionDetails"];
    errors_.push_back("exception: " +
                      (d.contains("exception") && d["exception"].contains("description")
                           ? d["exception"]["description"].get<std::string>()
                           : d.value("text", "?")));
  } else if (method == "Runtime.consoleAPICalled" &&
             (p.value("type", "") == "error" || p.value("type", "") == "assert")) {
    std::string text = "console." + p.value("type", "") + ":";
    for (const auto& a : p["args"])
      text += " " + (a.contains("value") ? a["value"].dump() : a.value("description", "?"));
    errors_.push_back(text);
  } else if (method == "Log.entryAdded" && p["entry"].value("level", "") == "error") {
    errors_.push_back("log: " + p["entry"].value("text", "") + " " + p["entry"].value("url", ""));
  }
  events_.push_back(e);
}

json Browser::wait_for_reply(int id, double timeout_s) {
  const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const double left = std::chrono::duration<double>(end - Clock::now()).count();
    json m = receive(std::max(left, 0.0));
    if (m.contains("id") && m["id"] == id) {
      if (m.contains("error")) throw std::runtime_error("DevTools: " + m["error"].dump());
      return m["result"];
    }
    note_event(m);
  }
}

json Browser::browser_call(const std::string& method, const json& params) {
  const int id = next_id_++;
  send({{"id", id}, {"method", method}, {"params", params}});
  return wait_for_reply(id, 60);
}

json Browser::call(const std::string& method, const json& params, double timeout_s) {
  const int id = next_id_++;
  send({{"id", id}, {"method", method}, {"params", params}, {"sessionId", session_}});
  return wait_for_reply(id, timeout_s);
}

void Browser::navigate(const std::string& url) {
  events_.clear();
  call("Page.navigate", {{"url", url}});
  const auto end = Clock::now() + std::chrono::seconds(60);
  for (;;) {
    for (const auto& e : events_)
      if (e.value("method", "") == "Page.loadEventFired") return;
    events_.clear();
    const double left = std::chrono::duration<double>(end - Clock::now()).count();
    note_event(receive(std::max(left, 0.0)));
  }
}

json Browser::evaluate(const std::string& expression, double timeout_s) {
  const json r = call("Runtime.evaluate",
                      {{"expression", expression}, {"awaitPromise", true}, {"returnByValue", true}},
                      timeout_s);
  if (r.contains("exceptionDetails")) {
    const json& d = r["exceptionDetails"];
    throw std::runtime_error(
        expression.substr(0, 80) + ": " +
        (d.contains("exception") ? d["exception"].value("description", "") : d.value("text", "")));
  }
  return r["result"].contains("value") ? r["result"]["value"] : json();
}

void Browser::click(double x, double y) {
  for (const char* type : {"mousePressed", "mouseReleased"})
    call("Input.dispatchMouseEvent", {{"type", type},
                                      {"x", x},
                                      {"y", y},
                                      {"button", "left"},
                                      {"buttons", std::strcmp(type, "mousePressed") == 0 ? 1 : 0},
                                      {"clickCount", 1}});
}

Image Browser::screenshot() {
  const std::vector<uint8_t> png =
      base64_decode(call("Page.captureScreenshot", {{"format", "png"}})["data"].get<std::string>());
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&img, png.data(), png.size()))
    throw std::runtime_error("screenshot: not a PNG");
  return finish_png(img, "screenshot");
}

}  // namespace chladni::test

namespace chladni::test {

std::vector<uint8_t> base64_decode(const std::string& s) {
  std::vector<uint8_t> out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    int v;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    else
      continue;
    acc = acc << 6 | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(uint8_t(acc >> bits & 0xff));
    }
  }
  return out;
}

Image read_png(const std::string& path) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str()))
    throw std::runtime_error(path + ": not a readable PNG");
  return finish_png(img, path);
}

}  // namespace chladni::test
