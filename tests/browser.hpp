#pragma once
// Headless Chromium driven over the DevTools protocol through --remote-debugging-pipe (JSON
// messages ending in NUL on file descriptors 3 and 4): no Node.js, no WebSocket library. Collects
// every console error, uncaught exception and error log entry of the page.
#include <sys/types.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace chladni::test {

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
  const uint8_t* at(int x, int y) const { return &rgba[(std::size_t(y) * width + x) * 4]; }
};

class Browser {
 public:
  /// Starts $CHLADNI_CHROMIUM (default /usr/bin/chromium) with a `width` x `height` window;
  /// throws std::runtime_error saying why it could not.
  Browser(int width = 1280, int height = 1000);
  ~Browser();
  Browser(const Browser&) = delete;
  Browser& operator=(const Browser&) = delete;

  /// A DevTools command on the page; throws on a protocol error or after `timeout_s`.
  nlohmann::json call(const std::string& method,
                      const nlohmann::json& params = nlohmann::json::object(),
                      double timeout_s = 60);
  /// Loads `url` and waits for its load event.
  void navigate(const std::string& url);
  /// The value of a JavaScript expression (promises awaited); throws with the page's exception.
  nlohmann::json evaluate(const std::string& expression, double timeout_s = 60);
  /// A left click at page coordinates (CSS px), as a user's mouse would.
  void click(double x, double y);
  Image screenshot();
  /// Console errors, uncaught exceptions and error log entries so far.
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  void attach();
  void shutdown();
  nlohmann::json browser_call(const std::string& method,
                              const nlohmann::json& params = nlohmann::json::object());
  void send(const nlohmann::json& message);
  nlohmann::json receive(double timeout_s);
  nlohmann::json wait_for_reply(int id, double timeout_s);
  void note_event(const nlohmann::json& event);

  pid_t pid_ = -1;
  int to_browser_ = -1, from_browser_ = -1;
  int next_id_ = 1;
  std::string session_, profile_, pending_;
  std::vector<nlohmann::json> events_;
  std::vector<std::string> errors_;
};

}  // namespace chladni::test

namespace chladni::test {

/// The bytes of base64 text (characters outside the alphabet are skipped).
std::vector<uint8_t> base64_decode(const std::string& text);

/// A PNG file as RGBA; throws std::runtime_error naming the file when it cannot.
Image read_png(const std::string& path);

}  // namespace chladni::test
