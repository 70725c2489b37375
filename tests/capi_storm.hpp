#pragma once
// A game's scene changing under the C API while the caller renders: a control thread spawning
// and removing objects (about a thousand of each per second) from banks it loads and releases,
// adding gravel to a third of them and taking some of it out again, and scraping another third
// (a continuous contact removed with its object), and a game thread posting impacts, moves,
// shakes and contact states to whichever objects, shakers and contacts are live. Shared by the
// thread test (under ThreadSanitizer) and the allocation test (counting on the audio thread).
#include <atomic>
#include <chrono>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "chladni/chladni.h"

namespace chladni::test {

/// The storm's runtime: the CPU backend on one thread, room for kLive objects and their fades.
inline chladni_runtime* storm_runtime() {
  chladni_config c;
  chladni_config_default(&c);
  c.threads = 1;
  c.max_objects = 64;
  c.contact_slots = 4096;
  chladni_runtime* rt = nullptr;
  return chladni_runtime_create(&c, &rt) == CHLADNI_OK ? rt : nullptr;
}

class CApiStorm {
 public:
  static constexpr int kLive = 24;  // objects alive at once; config.max_objects must exceed it

  explicit CApiStorm(chladni_runtime* rt) : rt_(rt) {
    for (auto& id : live_) id.store(0);
    for (auto& id : gravel_) id.store(0);
    for (auto& id : scrapes_) id.store(0);
  }
  ~CApiStorm() { stop(); }

  void start() {
    control_ = std::thread([this] { control(); });
    game_ = std::thread([this] { game(); });
  }
  void stop() {
    running_.store(false);
    if (control_.joinable()) control_.join();
    if (game_.joinable()) game_.join();
  }
  /// Removes what is left and releases every bank (after stop()).
  void clear() {
    for (auto& id : gravel_)
      if (const uint64_t v = id.exchange(0)) note(chladni_shaker_remove(rt_, {v}), "remove shaker");
    for (auto& id : scrapes_)
      if (const uint64_t v = id.exchange(0))
        note(chladni_contact_remove(rt_, {v}), "remove contact");
    for (auto& id : live_)
      if (const uint64_t v = id.exchange(0)) note(chladni_object_remove(rt_, {v}), "remove");
    for (chladni_bank b : banks_) note(chladni_bank_release(rt_, b), "release");
    banks_.clear();
  }

  std::atomic<long> spawned{0}, removed{0}, loaded{0}, released{0}, impacts{0}, moves{0}, shaken{0},
      shakers_added{0}, shakers_removed{0}, contacts_added{0}, contact_states{0}, gone{0}, full{0};
  std::string unexpected;  // the first status no caller should see (control thread's)
  std::atomic<bool> game_unexpected{false};

 private:
  void note(chladni_status s, const char* what) {
    if (s != CHLADNI_OK && unexpected.empty())
      unexpected = std::string(what) + ": " + chladni_last_error();
  }
  chladni_bank load(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<double> hz(40), decay(40), amp(40);
    const double f0 = 100 + 400 * u(rng);
    for (std::size_t i = 0; i < hz.size(); ++i) {
      hz[i] = f0 * (1 + 0.37 * i);  // below 8 kHz
      decay[i] = 5 + 20 * u(rng);
      amp[i] = 0.01 / (1 + i);
    }
    chladni_bank b{0};
    note(chladni_bank_from_modes(rt_, hz.data(), decay.data(), amp.data(), hz.size(), &b), "load");
    ++loaded;
    return b;
  }
  void control() {
    std::mt19937 rng(11);
    const double q[4] = {1, 0, 0, 0};
    banks_ = {load(rng), load(rng), load(rng)};
    for (long n = 0; running_.load(); ++n) {
      std::atomic<uint64_t>& place = live_[n % kLive];
      gravel_[n % kLive].store(0);                             // goes with its object
      if (const uint64_t c = scrapes_[n % kLive].exchange(0))  // ends with it, freed here
        note(chladni_contact_remove(rt_, {c}), "remove contact");
      if (const uint64_t old = place.exchange(0)) {
        note(chladni_object_remove(rt_, {old}), "remove");
        ++removed;
      }
      const double at[3] = {0.1 * (n % 7), 1.0, 0.0};
      chladni_object o{0};
      const chladni_status s =
          chladni_object_spawn(rt_, banks_[n % banks_.size()], at, q, 0.5 + 0.5 * (n % 3), &o);
      if (s == CHLADNI_OK) {
        place.store(o.id);
        ++spawned;
        if (n % 3 == 0) add_gravel(o, gravel_[n % kLive]);
        if (n % 3 == 1) add_scrape(o, scrapes_[n % kLive]);
      } else if (s == CHLADNI_QUEUE_FULL) {
        ++full;  // every place is alive or fading out: the audio thread is behind
      } else {
        note(s, "spawn");
      }
      if (n % 7 == 3) {  // some gravel taken out while its object plays on
        if (const uint64_t g = gravel_[(n * 5) % kLive].exchange(0)) {
          note(chladni_shaker_remove(rt_, {g}), "remove shaker");
          ++shakers_removed;
        }
      }
      if (n % 50 == 49) {  // a new bank in, the oldest given up while its objects play on
        note(chladni_bank_release(rt_, banks_.front()), "release");
        ++released;
        banks_.erase(banks_.begin());
        banks_.push_back(load(rng));
      }
      std::this_thread::sleep_for(std::chrono::microseconds(900));
    }
  }
  void add_gravel(chladni_object o, std::atomic<uint64_t>& into) {
    const chladni_shaker_desc d{o, "gravel", 0, 1, 0};
    chladni_shaker g{0};
    const chladni_status s = chladni_shaker_add(rt_, &d, &g);
    if (s == CHLADNI_OK) {
      into.store(g.id);
      ++shakers_added;
    } else if (s == CHLADNI_QUEUE_FULL) {
      ++full;
    } else {
      note(s, "add shaker");
    }
  }
  void add_scrape(chladni_object o, std::atomic<uint64_t>& into) {
    chladni_contact_desc d{};
    d.object = o;
    d.surface = "stone";
    chladni_contact c{0};
    const chladni_status s = chladni_contact_add(rt_, &d, &c);
    if (s == CHLADNI_OK) {
      into.store(c.id);
      ++contacts_added;
    } else if (s == CHLADNI_QUEUE_FULL) {
      ++full;  // every contact place is alive or ringing down
    } else {
      note(s, "add contact");
    }
  }
  void game() {
    std::mt19937 rng(5);
    const double q[4] = {1, 0, 0, 0};
    for (long n = 0; running_.load(); ++n) {
      const uint64_t id = live_[rng() % kLive].load();
      if (!id) continue;
      const double t = chladni_runtime_time(rt_) + 0.002;
      chladni_status s;
      if (n % 7 == 6) {
        const uint64_t c = scrapes_[rng() % kLive].load();
        if (!c) continue;
        chladni_contact_state st{};
        st.time = t;
        st.normal_force = 1 + 0.1 * (n % 10);
        st.slip_speed = 0.05 * (n % 8);
        st.rolling_speed = 0.02 * (n % 5);
        s = chladni_contact_post(rt_, {c}, &st);
        if (s == CHLADNI_OK) ++contact_states;
      } else if (n % 5 == 4) {
        const uint64_t g = gravel_[rng() % kLive].load();
        if (!g) continue;
        s = chladni_shaker_shake(rt_, {g}, t, 0.5);
        if (s == CHLADNI_OK) ++shaken;
      } else if (n % 2 == 0) {
        chladni_impact im{};
        im.object = {id};
        im.time = t;
        im.impulse = 0.01;
        im.direction[2] = -1;
        im.vertex = -1;
        im.contact_time = n % 4 ? 0.0 : 0.0005;
        s = chladni_impact_post(rt_, &im);
        if (s == CHLADNI_OK) ++impacts;
      } else {
        const double at[3] = {0.001 * (n % 100), 1.0, 0.0};
        s = chladni_object_move(rt_, {id}, t, at, q);
        if (s == CHLADNI_OK) ++moves;
      }
      if (s == CHLADNI_INPUT_ERROR)
        ++gone;  // removed after it was read (or its object was): refused, as it must be
      else if (s == CHLADNI_QUEUE_FULL)
        ++full;
      else if (s != CHLADNI_OK)
        game_unexpected.store(true);
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }

  chladni_runtime* rt_;
  std::atomic<bool> running_{true};
  std::atomic<uint64_t> live_[kLive], gravel_[kLive], scrapes_[kLive];
  std::vector<chladni_bank> banks_;
  std::thread control_, game_;
};

}  // namespace chladni::test
