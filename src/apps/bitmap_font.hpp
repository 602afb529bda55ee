#pragma once
// The tools' own bitmap font: one 5 x 9 glyph for each printable ASCII
// character (32..126), drawn for this project, so a figure can carry its
// axes, legend and figures without a font file or a rasteriser on the robot.
// Rows 0..6 hold capitals and digits (row 6 is the baseline), rows 7..8 the
// descenders of g j p q y , ; _ and the bar |. Anything outside 32..126
// draws as a hollow box, so a missing character is visible rather than
// silently dropped.
#include <string_view>

namespace rtfuse::apps {

// Pixels at scale 1; a text drawn at scale s has every pixel as an s x s block.
inline constexpr int kGlyphWidth = 5;
inline constexpr int kGlyphHeight = 9;
inline constexpr int kGlyphAdvance = kGlyphWidth + 1;  // one blank column between glyphs
inline constexpr int kCapHeight = 7;                   // rows 0..6
inline constexpr int kLineSpacing = kGlyphHeight + 3;  // baseline to baseline of stacked lines

// Whether the glyph of c has ink at column col (0..4), row row (0..8);
// false outside the cell.
bool glyph_ink(char c, int col, int row) noexcept;

// Width in pixels of one line of text at a scale: the advance of every
// glyph but the last, which ends at its ink (no trailing blank column).
// 0 for an empty text.
int text_width(std::string_view text, int scale) noexcept;

// Height in pixels of one line of text at a scale: the full cell, descenders
// included.
constexpr int text_height(int scale) noexcept { return kGlyphHeight * scale; }

}  // namespace rtfuse::apps
