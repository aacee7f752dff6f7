#include "activation_plot.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace sinew::fit {
namespace {

using postprocess::Image;
using postprocess::Rgb;

// A line of width 2 from (x0, y0) to (x1, y1).
void line(Image& img, double x0, double y0, double x1, double y1, Rgb c) {
  const int steps = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
  for (int i = 0; i <= steps; ++i) {
    const double t = static_cast<double>(i) / steps;
    const int x = static_cast<int>(std::lround(x0 + t * (x1 - x0)));
    const int y = static_cast<int>(std::lround(y0 + t * (y1 - y0)));
    img.set(x, y, c);
    img.set(x + 1, y, c);
    img.set(x, y + 1, c);
  }
}

Rgb palette(std::size_t i) {
  static const Rgb colours[] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},
                                {148, 103, 189}, {140, 86, 75},  {227, 119, 194}, {127, 127, 127},
                                {188, 189, 34},  {23, 190, 207}, {0, 0, 128},    {128, 0, 0}};
  const Rgb c = colours[i % 12];
  if (i / 12 % 2 == 0) return c;
  return {static_cast<std::uint8_t>(c.r / 2), static_cast<std::uint8_t>(c.g / 2),
          static_cast<std::uint8_t>(c.b / 2)};
}

struct Panel {
  int x, y, w, h;
  double t_end, v_max;
  double px(double t) const { return x + w * t / t_end; }
  double py(double v) const { return y + h - h * v / v_max; }
};

void axes(Image& img, const Panel& p, const std::string& title, const std::string& top_label) {
  const Rgb black{0, 0, 0}, grey{220, 220, 220};
  for (int i = 1; i < 4; ++i) {
    const double v = p.v_max * i / 4;
    line(img, p.x, p.py(v), p.x + p.w, p.py(v), grey);
  }
  line(img, p.x, p.y, p.x, p.y + p.h, black);
  line(img, p.x, p.y + p.h, p.x + p.w, p.y + p.h, black);
  postprocess::draw_text(img, p.x, p.y - 22, title, black, 2);
  postprocess::draw_text(img, p.x - 8 - postprocess::text_width(top_label, 2), p.y, top_label,
                         black, 2);
  postprocess::draw_text(img, p.x - 20, p.y + p.h - 14, "0", black, 2);
  const std::string end = fmt::format("{:.3g} S", p.t_end);
  postprocess::draw_text(img, p.x + p.w - postprocess::text_width(end, 2), p.y + p.h + 8, end,
                         black, 2);
}

}  // namespace

postprocess::Image draw_activation_plot(const FitResult& r) {
  const int left = 110, plot_w = 760;
  int legend_w = 0;
  for (const auto& m : r.muscles) legend_w = std::max(legend_w, postprocess::text_width(m, 2));
  const int width = std::max(1000, left + plot_w + 52 + legend_w + 20);
  const int legend_rows = static_cast<int>(r.muscles.size());
  const int top_h = std::max(420, legend_rows * 20 + 40), err_h = 200;
  Image img(width, top_h + err_h + 140, {255, 255, 255});
  double t_end = r.knot_times.empty() ? 1 : r.knot_times.back();
  if (!r.frame_times.empty()) t_end = std::max(t_end, r.frame_times.back());
  if (!(t_end > 0)) t_end = 1;
  double a_max = 0;
  for (const auto& c : r.activations)
    for (const double v : c) a_max = std::max(a_max, v);
  a_max = a_max > 0 ? std::ceil(a_max * 10 + 1e-9) / 10 : 1;
  const Panel act{left, 50, plot_w, top_h - 40, t_end, a_max};
  axes(img, act, "FITTED ACTIVATIONS", fmt::format("{:.1f}", a_max));
  for (std::size_t k = 0; k < r.activations.size(); ++k) {
    const auto& c = r.activations[k];
    for (std::size_t j = 1; j < c.size(); ++j)
      line(img, act.px(r.knot_times[j - 1]), act.py(c[j - 1]), act.px(r.knot_times[j]),
           act.py(c[j]), palette(k));
    const int ly = act.y + 20 * static_cast<int>(k);
    img.fill_rect(left + plot_w + 20, ly + 4, 24, 6, palette(k));
    postprocess::draw_text(img, left + plot_w + 52, ly, r.muscles[k], {0, 0, 0}, 2);
  }
  double e_max = 0;
  for (const double v : r.frame_rms_mm)
    if (std::isfinite(v)) e_max = std::max(e_max, v);
  e_max = e_max > 0 ? e_max * 1.1 : 1;
  const Panel err{left, top_h + 90, plot_w, err_h, t_end, e_max};
  axes(img, err, fmt::format("MARKER RMS ERROR PER FRAME (MM), ALL: {:.3f} MM", r.rms_mm),
       fmt::format("{:.2f}", e_max));
  bool have = false;
  double px = 0, py = 0;
  for (std::size_t f = 0; f < r.frame_times.size(); ++f) {
    if (!std::isfinite(r.frame_rms_mm[f])) {
      have = false;
      continue;
    }
    const double x = err.px(r.frame_times[f]), y = err.py(r.frame_rms_mm[f]);
    if (have) line(img, px, py, x, y, {214, 39, 40});
    px = x;
    py = y;
    have = true;
  }
  return img;
}

}  // namespace sinew::fit
