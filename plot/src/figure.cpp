#include "chladni/plot/figure.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"

namespace chladni::plot {
namespace {

constexpr double kFont = 13;

// Inferno-like: black, purple, red, orange, pale yellow.
Colour colour_map(double u) {
  static const double stops[5][3] = {
      {0, 0, 4}, {87, 16, 110}, {188, 55, 84}, {249, 142, 9}, {252, 255, 164}};
  u = std::clamp(u, 0.0, 1.0) * 4;
  const int i = std::min(int(u), 3);
  const double t = u - i;
  Colour c;
  c.r = (stops[i][0] * (1 - t) + stops[i + 1][0] * t) / 255;
  c.g = (stops[i][1] * (1 - t) + stops[i + 1][1] * t) / 255;
  c.b = (stops[i][2] * (1 - t) + stops[i + 1][2] * t) / 255;
  return c;
}

std::string tick_text(double v) {
  char text[32];
  const double a = std::abs(v);
  if (a >= 1000 && std::abs(v / 1000 - std::round(v / 1000)) < 1e-9)
    std::snprintf(text, sizeof text, "%gk", v / 1000);
  else if (a != 0 && (a < 1e-2 || a >= 1e5))
    std::snprintf(text, sizeof text, "%.0e", v);
  else
    std::snprintf(text, sizeof text, "%g", v);
  return text;
}

// Tick values: 1, 2, 5 x 10^k on a log axis (1 x 10^k alone past three decades), a step of
// 1, 2 or 5 x 10^k giving 4-8 ticks on a linear one.
std::vector<double> ticks(const Axis& a) {
  std::vector<double> out;
  if (a.log) {
    const bool sparse = a.hi / a.lo > 1e3;
    for (int e = int(std::floor(std::log10(a.lo))); e <= int(std::ceil(std::log10(a.hi))); ++e)
      for (double m : {1.0, 2.0, 5.0}) {
        const double v = m * std::pow(10.0, e);
        if ((!sparse || m == 1.0) && v >= a.lo * (1 - 1e-9) && v <= a.hi * (1 + 1e-9))
          out.push_back(v);
      }
    return out;
  }
  const double span = a.hi - a.lo;
  double step = std::pow(10.0, std::floor(std::log10(span)) - 1);  // the finest that fits
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (span / (step * m) <= 8) {
      step *= m;
      break;
    }
  for (double v = std::ceil(a.lo / step) * step; v <= a.hi + 1e-9 * span; v += step)
    out.push_back(std::abs(v) < 1e-12 * span ? 0.0 : v);
  return out;
}

double unit(const Axis& a, double v) {
  return a.log ? std::log(v / a.lo) / std::log(a.hi / a.lo) : (v - a.lo) / (a.hi - a.lo);
}

}  // namespace

float Spectrogram::max_db() const {
  return db.empty() ? 0.f : *std::max_element(db.begin(), db.end());
}

struct Figure::Impl {
  cairo_surface_t* surface = nullptr;
  cairo_t* cr = nullptr;
  Rect area;
  Axis x, y;
  int legend = 0;

  double px(double v) const { return area.x + area.w * unit(x, v); }
  double py(double v) const { return area.y + area.h * (1 - unit(y, v)); }
  bool valid(double vx, double vy) const {
    return std::isfinite(vx) && std::isfinite(vy) && (!x.log || vx > 0) && (!y.log || vy > 0);
  }

  void text(double tx, double ty, const std::string& s, double align, double size = kFont) {
    cairo_set_font_size(cr, size);
    cairo_text_extents_t e;
    cairo_text_extents(cr, s.c_str(), &e);
    cairo_move_to(cr, tx - align * e.x_advance, ty);
    cairo_show_text(cr, s.c_str());
  }

  // Frame, ticks, tick labels, axis labels and title of the current panel.
  void axes(const std::string& title) {
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1);
    cairo_rectangle(cr, area.x, area.y, area.w, area.h);
    cairo_stroke(cr);
    for (double v : ticks(x)) {
      const double p = px(v);
      cairo_move_to(cr, p, area.y + area.h);
      cairo_line_to(cr, p, area.y + area.h + 5);
      cairo_stroke(cr);
      text(p, area.y + area.h + 18, tick_text(v), 0.5);
    }
    for (double v : ticks(y)) {
      const double p = py(v);
      cairo_move_to(cr, area.x - 5, p);
      cairo_line_to(cr, area.x, p);
      cairo_stroke(cr);
      text(area.x - 8, p + 4, tick_text(v), 1.0);
    }
    text(area.x + area.w / 2, area.y + area.h + 36, x.label, 0.5);
    cairo_save(cr);
    cairo_translate(cr, area.x - 52, area.y + area.h / 2);
    cairo_rotate(cr, -M_PI / 2);
    text(0, 0, y.label, 0.5);
    cairo_restore(cr);
    text(area.x + area.w / 2, area.y - 8, title, 0.5, kFont + 1);
  }

  void legend_entry(Colour c, const std::string& label, bool dot) {
    if (label.empty()) return;
    const double lx = area.x + 12, ly = area.y + 18 + 17 * legend++;
    cairo_set_source_rgb(cr, c.r, c.g, c.b);
    if (dot) {
      cairo_arc(cr, lx + 10, ly - 4, 3.5, 0, 2 * M_PI);
      cairo_fill(cr);
    } else {
      cairo_set_line_width(cr, 2);
      cairo_move_to(cr, lx, ly - 4);
      cairo_line_to(cr, lx + 20, ly - 4);
      cairo_stroke(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    text(lx + 26, ly, label, 0, kFont - 1);
  }
};

Figure::Figure(int width, int height, const std::string& title) : impl_(std::make_unique<Impl>()) {
  impl_->surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
  impl_->cr = cairo_create(impl_->surface);
  cairo_t* cr = impl_->cr;
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_source_rgb(cr, 0, 0, 0);
  impl_->text(width / 2.0, 24, title, 0.5, kFont + 3);
}

Figure::~Figure() {
  cairo_destroy(impl_->cr);
  cairo_surface_destroy(impl_->surface);
}

void Figure::panel(const Rect& r, const Axis& x, const Axis& y, const std::string& title) {
  impl_->area = r;
  impl_->x = x;
  impl_->y = y;
  impl_->legend = 0;
  impl_->axes(title);
}

void Figure::line(const std::vector<double>& x, const std::vector<double>& y, Colour c,
                  const std::string& label, double width) {
  Impl& m = *impl_;
  cairo_save(m.cr);
  cairo_rectangle(m.cr, m.area.x, m.area.y, m.area.w, m.area.h);
  cairo_clip(m.cr);
  cairo_set_source_rgb(m.cr, c.r, c.g, c.b);
  cairo_set_line_width(m.cr, width);
  bool open = false;
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i) {
    if (!m.valid(x[i], y[i])) {
      open = false;
      continue;
    }
    (open ? cairo_line_to : cairo_move_to)(m.cr, m.px(x[i]), m.py(y[i]));
    open = true;
  }
  cairo_stroke(m.cr);
  cairo_restore(m.cr);
  m.legend_entry(c, label, false);
}

void Figure::points(const std::vector<double>& x, const std::vector<double>& y,
                    const std::vector<double>& lo, const std::vector<double>& hi, Colour c,
                    const std::string& label) {
  Impl& m = *impl_;
  cairo_save(m.cr);
  cairo_rectangle(m.cr, m.area.x, m.area.y, m.area.w, m.area.h);
  cairo_clip(m.cr);
  cairo_set_source_rgb(m.cr, c.r, c.g, c.b);
  cairo_set_line_width(m.cr, 1.2);
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i) {
    if (!m.valid(x[i], y[i])) continue;
    if (i < lo.size() && i < hi.size()) {
      const double a = m.y.log ? std::max(lo[i], m.y.lo) : lo[i];
      cairo_move_to(m.cr, m.px(x[i]), m.py(a));
      cairo_line_to(m.cr, m.px(x[i]), m.py(hi[i]));
      cairo_stroke(m.cr);
    }
    cairo_arc(m.cr, m.px(x[i]), m.py(y[i]), 3.5, 0, 2 * M_PI);
    cairo_fill(m.cr);
  }
  cairo_restore(m.cr);
  m.legend_entry(c, label, true);
}

void Figure::spectrogram(const Rect& r, const Spectrogram& s, const std::string& title, double fmin,
                         double fmax, double top_db, double range_db, bool linear,
                         const Events& events) {
  Impl& m = *impl_;
  const double seconds = std::max(double(s.frames) * s.hop_s, 1e-3);
  m.area = r;
  m.x = {"time (s)", 0, seconds, false};
  m.y = {"frequency (Hz)", linear ? 0.0 : fmin, fmax, !linear};
  m.legend = 0;
  const int w = std::max(1, int(r.w)), h = std::max(1, int(r.h));
  cairo_surface_t* img = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
  unsigned char* data = cairo_image_surface_get_data(img);
  const int stride = cairo_image_surface_get_stride(img);
  // Each pixel shows the loudest cell it covers: a row spanning many bins (high on a log axis, or
  // a linear one) or a column spanning many frames loses no peak.
  auto bin_at = [&](double u) {
    const double f = linear ? fmax * u : fmin * std::pow(fmax / fmin, u);
    return std::min<std::size_t>(s.bins - 1, std::size_t(std::max(0.0, f / s.bin_hz + 0.5)));
  };
  for (int row = 0; row < h; ++row) {
    const std::size_t b1 = bin_at(1 - double(row) / h), b0 = bin_at(1 - (row + 1.0) / h);
    const std::size_t lo = b1 > b0 ? b0 : bin_at(1 - (row + 0.5) / h), hi = std::max(lo, b1);
    for (int col = 0; col < w; ++col) {
      double v = -1e9;
      if (s.frames) {
        const std::size_t f0 = std::min(s.frames - 1, std::size_t(col * double(s.frames) / w));
        const std::size_t f1 =
            std::max(f0 + 1, std::min(s.frames, std::size_t((col + 1) * double(s.frames) / w)));
        for (std::size_t f = f0; f < f1; ++f)
          for (std::size_t b = lo; b <= (b1 > b0 ? hi : lo); ++b)
            v = std::max(v, double(s.db[f * s.bins + b]));
      }
      const Colour c = colour_map(1 - (top_db - v) / range_db);
      auto* px = reinterpret_cast<uint32_t*>(data + row * stride) + col;
      *px = (uint32_t(c.r * 255) << 16) | (uint32_t(c.g * 255) << 8) | uint32_t(c.b * 255);
    }
  }
  cairo_surface_mark_dirty(img);
  cairo_set_source_surface(m.cr, img, r.x, r.y);
  cairo_paint(m.cr);
  cairo_surface_destroy(img);
  for (double t : events.times) {
    if (t < 0 || t > seconds) continue;
    cairo_set_source_rgb(m.cr, 0.3, 0.9, 1.0);
    const double dash[2] = {4, 3};
    cairo_set_dash(m.cr, dash, 2, 0);
    cairo_move_to(m.cr, m.px(t), r.y);
    cairo_line_to(m.cr, m.px(t), r.y + r.h);
    cairo_stroke(m.cr);
    cairo_set_dash(m.cr, nullptr, 0, 0);
  }
  if (!events.times.empty() && !events.label.empty()) {
    cairo_set_source_rgb(m.cr, 0.3, 0.9, 1.0);
    const double dash[2] = {4, 3};
    cairo_set_dash(m.cr, dash, 2, 0);
    cairo_move_to(m.cr, r.x + r.w - 150, r.y + 14);
    cairo_line_to(m.cr, r.x + r.w - 130, r.y + 14);
    cairo_stroke(m.cr);
    cairo_set_dash(m.cr, nullptr, 0, 0);
    m.text(r.x + r.w - 124, r.y + 18, events.label, 0, kFont - 1);
  }
  m.axes(title);
  // Colour bar.
  const double bx = r.x + r.w + 12, bw = 12;
  for (int row = 0; row < h; ++row) {
    const Colour c = colour_map(1 - (row + 0.5) / h);
    cairo_set_source_rgb(m.cr, c.r, c.g, c.b);
    cairo_rectangle(m.cr, bx, r.y + row, bw, 1);
    cairo_fill(m.cr);
  }
  cairo_set_source_rgb(m.cr, 0, 0, 0);
  cairo_rectangle(m.cr, bx, r.y, bw, r.h);
  cairo_stroke(m.cr);
  for (int k = 0; k <= 4; ++k) {
    const double y = r.y + r.h * k / 4.0;
    char label[32];
    std::snprintf(label, sizeof label, "%.0f", top_db - range_db * k / 4.0);
    m.text(bx + bw + 4, y + 4, label, 0, kFont - 2);
  }
  m.text(bx + bw / 2, r.y - 8, "dB", 0.5, kFont - 2);
}

void Figure::write_png(const std::string& path) {
  cairo_surface_flush(impl_->surface);
  const std::string tmp = temporary_path(path);
  if (cairo_surface_write_to_png(impl_->surface, tmp.c_str()) != CAIRO_STATUS_SUCCESS)
    throw InputError("cannot write " + path);
  commit_temporary(tmp, path, "plot");
}

}  // namespace chladni::plot
