// Legends and key-figure lines: each entry's swatch shows its series'
// colour where the row is, its label is inked right of it, the box is the
// size computed for it, and the error panel's legend states the RMS.
#include "apps/legend.hpp"

#include <gtest/gtest.h>

#include "apps/bitmap_font.hpp"
#include "apps/error_panel.hpp"

namespace rtfuse::apps {
namespace legend_test {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kRed{214, 39, 40};
constexpr Rgb kGreen{0, 150, 60};

int count(const Canvas& c, Rgb colour, const Rect& r) {
  int n = 0;
  for (int y = r.y; y < r.bottom(); ++y)
    for (int x = r.x; x < r.right(); ++x) n += c.at(x, y) == colour ? 1 : 0;
  return n;
}

TEST(Legend, SwatchesAndLabelsInTheirRows) {
  Canvas c(400, 200, Rgb{230, 230, 230});
  const std::vector<LegendEntry> entries = {{"ground truth", kRed, false, Marker::kDisc, 2, false},
                                            {"start", kGreen, true, Marker::kDisc, 2, false}};
  const int scale = 2;
  const Rect box = draw_legend(c, 20, 30, entries, scale);
  const Rect size = legend_box_size(entries, scale);
  EXPECT_EQ(box.x, 20);
  EXPECT_EQ(box.y, 30);
  EXPECT_EQ(box.w, size.w);
  EXPECT_EQ(box.h, size.h);
  EXPECT_EQ(c.at(box.x + box.w / 2, box.y + 2), kWhite) << "the box is filled";

  // Row k spans kLineSpacing * scale rows from the box' top padding; each
  // colour appears only in its own row's swatch column.
  const int row_h = kLineSpacing * scale;
  const int top = box.y + 8;  // the box' padding
  const Rect swatch0{box.x, top, kSwatchPx + 16, row_h}, swatch1{box.x, top + row_h, kSwatchPx + 16, row_h};
  EXPECT_GE(count(c, kRed, swatch0), 3 * (kSwatchPx - 4)) << "a line across the swatch, 3 pixels thick";
  EXPECT_EQ(count(c, kRed, swatch1), 0);
  EXPECT_GT(count(c, kGreen, swatch1), 20);
  EXPECT_EQ(count(c, kGreen, swatch0), 0);
  EXPECT_EQ(count(c, kRed, box) + count(c, kGreen, box), count(c, kRed, Rect{0, 0, 400, 200}) +
                                                             count(c, kGreen, Rect{0, 0, 400, 200}))
      << "nothing outside the box";
  // The labels: ink right of the swatches, as wide as the text.
  const int label_x = box.x + 8 + kSwatchPx + 8;
  EXPECT_GT(count(c, kBlack, Rect{label_x, top, text_width("ground truth", scale), text_height(scale)}), 50);
  EXPECT_EQ(count(c, kBlack, Rect{label_x + text_width("start", scale) + 1, top + row_h, 40, text_height(scale)}), 0);
}

TEST(Legend, RowIsAsWideAsComputed) {
  Canvas c(600, 40, kWhite);
  const std::vector<LegendEntry> entries = {{"a", kRed, false, Marker::kDisc, 2, false},
                                            {"bcd", kGreen, false, Marker::kDisc, 2, true}};
  const Rect r = draw_legend_row(c, 10, 10, entries, 2);
  EXPECT_EQ(r.w, legend_row_width(entries, 2));
  EXPECT_GT(count(c, kRed, Rect{10, 10, kSwatchPx, text_height(2)}), 0);
  const int second = 10 + kSwatchPx + 8 + text_width("a", 2) + 3 * kGlyphAdvance * 2;
  EXPECT_GT(count(c, kGreen, Rect{second, 10, kSwatchPx, text_height(2)}), 0);
  EXPECT_EQ(count(c, kGreen, Rect{0, 0, second, 40}), 0);
}

TEST(Legend, HeadingsAreBoldAndLinesStack) {
  Canvas plain(300, 100, kWhite), bold(300, 100, kWhite);
  const Rect r = draw_text_lines(plain, 5, 5, {"ATE", "RMS 0.3 m"}, kBlack, 2);
  draw_text_lines(bold, 5, 5, {"# ATE", "RMS 0.3 m"}, kBlack, 2);
  EXPECT_EQ(r.w, text_width("RMS 0.3 m", 2));
  EXPECT_EQ(r.h, kLineSpacing * 2 + text_height(2));
  const Rect first{0, 0, 300, 5 + text_height(2)};
  EXPECT_GT(count(bold, kBlack, first), count(plain, kBlack, first)) << "a heading has more ink";
  EXPECT_EQ(count(bold, kBlack, Rect{5 + text_width("ATE", 2) + 2, 0, 100, 5 + text_height(2)}), 0)
      << "without the '# '";
}

TEST(ErrorPanel, LegendStatesTheRms) {
  const ErrorSeries s{"visual odometry", kRed, {{0, 0.0}, {1, 0.2}}, 0.14142};
  EXPECT_EQ(error_series_label(s), "visual odometry (dashed: RMS 0.141 m)");
}

}  // namespace legend_test
}  // namespace rtfuse::apps
