// The tools' bitmap font and text drawing: a glyph decodes to the picture
// it was drawn as, text puts ink exactly where its glyphs have it at any
// scale and offset, and text_width / text_height are the ink's extent.
#include "apps/bitmap_font.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "apps/canvas.hpp"

namespace rtfuse::apps {
namespace bitmap_font_test {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kInk{10, 20, 30};

// 'H' and 'g' as drawn in bitmap_font.cpp, written out again here: the
// decoding (bit order, rows, the descender) must give back the picture.
TEST(BitmapFont, GlyphsDecodeToTheirPictures) {
  const std::vector<std::string> h = {"#...#", "#...#", "#...#", "#####", "#...#",
                                      "#...#", "#...#", ".....", "....."};
  const std::vector<std::string> g = {".....", ".....", ".####", "#...#", "#...#",
                                      "#...#", ".####", "....#", ".###."};
  for (int row = 0; row < kGlyphHeight; ++row)
    for (int col = 0; col < kGlyphWidth; ++col) {
      EXPECT_EQ(glyph_ink('H', col, row), h[row][col] == '#') << "H " << col << "," << row;
      EXPECT_EQ(glyph_ink('g', col, row), g[row][col] == '#') << "g " << col << "," << row;
    }
  EXPECT_FALSE(glyph_ink('H', -1, 0));
  EXPECT_FALSE(glyph_ink('H', kGlyphWidth, 3));
  EXPECT_FALSE(glyph_ink('H', 0, kGlyphHeight));
}

std::vector<int> bitmap(char c) {
  std::vector<int> bits;
  for (int row = 0; row < kGlyphHeight; ++row)
    for (int col = 0; col < kGlyphWidth; ++col) bits.push_back(glyph_ink(c, col, row) ? 1 : 0);
  return bits;
}

// A glyph mistyped into another's, or left empty, would print a wrong
// figure without anyone noticing.
TEST(BitmapFont, EveryPrintableGlyphHasInkAndIsDistinct) {
  std::set<std::vector<int>> seen;
  for (int c = 33; c <= 126; ++c) {
    const std::vector<int> bits = bitmap(static_cast<char>(c));
    int ink = 0;
    for (const int b : bits) ink += b;
    EXPECT_GT(ink, 0) << "'" << static_cast<char>(c) << "' has no ink";
    EXPECT_TRUE(seen.insert(bits).second) << "'" << static_cast<char>(c) << "' looks like another glyph";
  }
  int space = 0;
  for (const int b : bitmap(' ')) space += b;
  EXPECT_EQ(space, 0);
}

// Rows 7 and 8 are for descenders only: a capital or digit reaching into
// them would sit below its neighbours.
TEST(BitmapFont, OnlyDescendersReachBelowTheBaseline) {
  const std::string descenders = "gjpqy,;_|";
  for (int c = 32; c <= 126; ++c) {
    bool below = false;
    for (int row = kCapHeight; row < kGlyphHeight; ++row)
      for (int col = 0; col < kGlyphWidth; ++col) below = below || glyph_ink(static_cast<char>(c), col, row);
    EXPECT_EQ(below, descenders.find(static_cast<char>(c)) != std::string::npos) << "'" << static_cast<char>(c) << "'";
  }
}

// Characters the font lacks draw as one visible box, not as nothing.
TEST(BitmapFont, MissingCharactersDrawTheBox) {
  const std::vector<int> box = bitmap('\x7f');
  EXPECT_EQ(bitmap('\xc3'), box);
  EXPECT_EQ(bitmap('\t'), box);
  EXPECT_NE(bitmap('O'), box);
  EXPECT_TRUE(glyph_ink('\xc3', 0, 0));
  EXPECT_TRUE(glyph_ink('\xc3', kGlyphWidth - 1, kCapHeight - 1));
  EXPECT_FALSE(glyph_ink('\xc3', 2, 3));
}

// Every pixel of the canvas: ink exactly where the glyph has it, scaled to
// s x s blocks, advancing kGlyphAdvance * s per character.
TEST(BitmapFont, TextInkIsExactlyTheGlyphsScaled) {
  const std::string text = "x=-1.5 m";
  for (const int scale : {1, 2, 3}) {
    Canvas canvas(200, 60, kWhite);
    const int x0 = 7, y0 = 5;
    EXPECT_EQ(canvas.text(x0, y0, text, kInk, scale), text_width(text, scale));
    int wrong = 0;
    for (int y = 0; y < canvas.height(); ++y)
      for (int x = 0; x < canvas.width(); ++x) {
        bool ink = false;
        const int dx = x - x0, dy = y - y0;
        if (dx >= 0 && dy >= 0) {
          const int i = dx / (kGlyphAdvance * scale);
          const int col = (dx % (kGlyphAdvance * scale)) / scale, row = dy / scale;
          ink = i < static_cast<int>(text.size()) && glyph_ink(text[static_cast<std::size_t>(i)], col, row);
        }
        if ((canvas.at(x, y) == kInk) != ink && ++wrong <= 5)
          ADD_FAILURE() << "scale " << scale << " pixel (" << x << ", " << y << ")";
      }
    EXPECT_EQ(wrong, 0);
  }
}

struct InkBox {
  int x0 = 1 << 20, y0 = 1 << 20, x1 = -1, y1 = -1;
  int width() const { return x1 - x0 + 1; }
  int height() const { return y1 - y0 + 1; }
};

InkBox ink_box(const Canvas& canvas) {
  InkBox b;
  for (int y = 0; y < canvas.height(); ++y)
    for (int x = 0; x < canvas.width(); ++x)
      if (canvas.at(x, y) == kInk) {
        b.x0 = std::min(b.x0, x), b.x1 = std::max(b.x1, x);
        b.y0 = std::min(b.y0, y), b.y1 = std::max(b.y1, y);
      }
  return b;
}

// 'H' has ink in its first and last column and from the top row, 'g' in
// the last row: their ink spans exactly the computed width and height.
TEST(BitmapFont, WidthAndHeightAreTheInksExtent) {
  for (const int scale : {1, 2, 4}) {
    Canvas canvas(300, 80, kWhite);
    canvas.text(11, 13, "HgH", kInk, scale);
    const InkBox b = ink_box(canvas);
    EXPECT_EQ(b.x0, 11);
    EXPECT_EQ(b.y0, 13);
    EXPECT_EQ(b.width(), text_width("HgH", scale)) << "scale " << scale;
    EXPECT_EQ(b.height(), text_height(scale)) << "scale " << scale;
  }
  EXPECT_EQ(text_width("HgH", 2), (3 * kGlyphAdvance - 1) * 2);
  EXPECT_EQ(text_width("", 3), 0);
  EXPECT_EQ(text_width("abc", 0), 0);
}

// Text running off the canvas (or out of the clip) is cut, not wrapped or
// shifted: what is left is the window of the same text on a larger canvas.
TEST(BitmapFont, TextIsClippedToTheCanvasAndTheClip) {
  Canvas small(20, 12, kWhite), large(60, 52, kWhite);
  small.text(-8, -3, "WgW", kInk, 2);
  small.text(14, 6, "M", kInk, 2);
  large.text(12, 17, "WgW", kInk, 2);
  large.text(34, 26, "M", kInk, 2);
  int wrong = 0, ink = 0;
  for (int y = 0; y < small.height(); ++y)
    for (int x = 0; x < small.width(); ++x) {
      wrong += small.at(x, y) != large.at(x + 20, y + 20) ? 1 : 0;
      ink += small.at(x, y) == kInk ? 1 : 0;
    }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(ink, 0);

  Canvas clipped(60, 20, kWhite);
  clipped.set_clip(Rect{10, 0, 10, 20});
  clipped.text(0, 0, "HHHHHHHHHH", kInk, 1);
  const InkBox c = ink_box(clipped);
  EXPECT_EQ(c.x0, 10);  // the last column of the second H
  EXPECT_EQ(c.x1, 19);  // the crossbar of the fourth
}

}  // namespace bitmap_font_test
}  // namespace rtfuse::apps
