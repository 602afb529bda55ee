// The dense matcher's vector loops (semi_global_matcher.hpp): the fused
// selection, the path costs and the two passes over the image, written
// once over a lane backend (simd_u8.hpp's 16 lanes, simd_avx2.hpp's 32)
// and compiled once per instruction set. Deliberately no include guard
// and no includes: semi_global_matcher.cpp puts it inside a namespace of
// its own per instruction set, the AVX2 one between RTFUSE_AVX2_BEGIN and
// RTFUSE_AVX2_END (simd_avx2.hpp says why), after census_cost_kernels.hpp
// in the same namespace and after defining kPathBeyondRange and
// kSlotFirst (the path rows' layout). Every backend computes the same
// integers: the lane count changes how many disparities a step takes,
// never a value.

// The selection of packed_winner.hpp for one row, pixel by pixel as the
// upward pass finishes each pixel's sums. L: 16-bit lanes.
template <class L>
class PackedWinner {
 public:
  using V = typename L::V;
  static constexpr std::int16_t kNone = 0x7fff;

  // right: the row's right-view scratch, width + disparities values,
  // indexed width - 1 - (right column) as in DisparityRowScratch.
  // disparities: a multiple of L::kLanes.
  PackedWinner(int width, int disparities, int uniqueness_percent, std::int16_t* right) noexcept
      : width_(width),
        disparities_(disparities),
        uniqueness_percent_(uniqueness_percent),
        shift_(packed_winner_shift(disparities)),
        right_(right) {
    static const std::int16_t kLane[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
    static_assert(L::kLanes <= 16, "one lane index per lane");
    lane_bias_ = L::add(L::load(kLane), L::splat(-32768));
    std::fill(right_, right_ + width + disparities, kNone);
  }

  // Starts left pixel x; its sums follow L::kLanes disparities a call, in
  // order.
  void begin(int x) noexcept {
    x_ = x;
    cut_ = x < disparities_ - 1;
    last_ = L::splat(x - 32768);
    bias_ = lane_bias_;
    min1_ = min2_ = L::splat(kNone);
    right_x_ = right_ + (width_ - 1 - x);
  }

  // Sums of disparities k .. k + L::kLanes - 1.
  void add(int k, V sums) noexcept {
    V packed = L::add(L::shl(sums, shift_), bias_);
    // Past x the disparity looks left of the right image.
    if (cut_) packed = L::select(L::gt(bias_, last_), L::splat(kNone), packed);
    L::store(right_x_ + k, L::min(L::load(right_x_ + k), packed));
    min2_ = L::min(min2_, L::max(min1_, packed));
    min1_ = L::min(min1_, packed);
    bias_ = L::add(bias_, L::splat(L::kLanes));
  }

  // The pixel's disparity * kDisparityScale or -1 into *out, its winner or
  // -1 into *best_out; sums: the pixel's disparities' sums (for the
  // fraction).
  void finish(const std::int16_t* sums, std::int16_t* out, std::int16_t* best_out) const noexcept {
    const int mask = (1 << shift_) - 1;
    const unsigned least_packed = unpack(L::hmin(min1_));
    const int best = static_cast<int>(least_packed) & mask, least = static_cast<int>(least_packed >> shift_);
    if (uniqueness_percent_ > 0) {
      const V d = L::bit_and(min1_, L::splat(mask));
      const V near = L::select(L::gt(d, L::splat(best - 2)), L::gt(L::splat(best + 2), d), L::splat(0));
      const int second = L::hmin(L::select(near, min2_, min1_));
      if (second != kNone && static_cast<int>(unpack(second) >> shift_) < uniqueness_bar(least)) {
        *out = -1;
        *best_out = -1;
        return;
      }
    }
    *best_out = static_cast<std::int16_t>(best);
    const int dmax = std::min(disparities_ - 1, x_);
    const int fraction = best > 0 && best < dmax ? subpixel_offset(sums[best - 1], least, sums[best + 1]) : 0;
    *out = static_cast<std::int16_t>(best * kDisparityScale + fraction);
  }

  // After every pixel of the row: drops those whose right-view winner
  // differs by more than lr_max_diff (< 0: no check).
  void check_right(const std::int16_t* best, int lr_max_diff, std::int16_t* out) const noexcept {
    if (lr_max_diff < 0) return;
    const int mask = (1 << shift_) - 1;
    for (int x = 0; x < width_; ++x) {
      const int d = best[x];
      if (d < 0) continue;
      const int right_best = static_cast<int>(unpack(right_[width_ - 1 - x + d])) & mask;
      if (std::abs(right_best - d) > lr_max_diff) out[x] = -1;
    }
  }

 private:
  static unsigned unpack(int biased) noexcept { return static_cast<unsigned>(biased + 32768); }
  // s * (100 - u) < least * 100 for an integer s exactly when s < this.
  int uniqueness_bar(int least) const noexcept {
    const int keep = 100 - uniqueness_percent_;
    return (least * 100 + keep - 1) / keep;
  }

  int width_, disparities_, uniqueness_percent_, shift_;
  std::int16_t* right_;
  std::int16_t* right_x_ = nullptr;
  int x_ = 0;
  bool cut_ = false;
  V lane_bias_, last_, bias_, min1_, min2_;
};

// A whole row through PackedWinner, in the matcher's order (right to
// left): the tests hold it against select_disparity_row.
template <class L>
inline void select_row_packed(const std::int16_t* sums, int width, int disparities, int uniqueness_percent,
                              int lr_max_diff, const DisparityRowScratch& scratch, std::int16_t* out) noexcept {
  PackedWinner<L> winner(width, disparities, uniqueness_percent, scratch.right_cost);
  for (int x = width - 1; x >= 0; --x) {
    const std::int16_t* s = sums + static_cast<std::ptrdiff_t>(x) * disparities;
    winner.begin(x);
    for (int k = 0; k < disparities; k += L::kLanes) winner.add(k, L::load(s + k));
    winner.finish(s, out + x, scratch.left_best + x);
  }
  winner.check_right(scratch.left_best, lr_max_diff, out);
}

// One pixel of two paths: their new costs from their previous pixels' and
// the pixel's matching costs, B::kLanes disparities a step; the two paths'
// sum (bytes) goes to sink(k, sum of k .. k + B::kLanes - 1). Two paths a
// sweep (a pass's four take two sweeps): with more, their vectors no
// longer fit the sixteen registers of SSE2 or AVX2 and spill.
template <class B, bool kRowPath, class Sink>
inline void update_path_pair(const std::uint8_t* const* prev, std::uint8_t* const* cur, const std::uint8_t* cost,
                             int disparities, typename B::V p1, typename B::V jump, Sink&& sink) noexcept {
  using V = typename B::V;
  // Every candidate is at least the previous least (base), so subtracting
  // it first cannot wrap, and the jump is then the constant P2.
  const V base[2] = {B::splat(prev[0][0]), B::splat(prev[1][0])};
  V least[2] = {B::splat(kPathBeyondRange), B::splat(kPathBeyondRange)};
  // The row path (path 0 if kRowPath): its previous pixel's costs were
  // stored just now, and a load one byte off a recent store cannot be
  // forwarded from the store buffer (a stall of every such load). Its
  // neighbours d - 1 and d + 1 are therefore shifted in from the chunks on
  // either side, loaded where they were stored.
  V row_before = B::splat(kPathBeyondRange), row_at = B::load(prev[0] + kSlotFirst);
  for (int k = 0; k < disparities; k += B::kLanes) {
    const V c = B::load(cost + k);
    // Past the range: the slot's beyond-range guard, not written since.
    const V row_after = kRowPath ? B::load(prev[0] + kSlotFirst + k + B::kLanes) : row_at;
    V pair = B::splat(0);
#pragma GCC unroll 2
    for (int i = 0; i < 2; ++i) {
      const std::uint8_t* p = prev[i] + kSlotFirst + k;
      const bool row = kRowPath && i == 0;
      const V at = row ? row_at : B::load(p);
      const V before = row ? B::shift_in_before(row_at, row_before) : B::load(p - 1);
      const V after = row ? B::shift_in_after(row_at, row_after) : B::load(p + 1);
      const V m = B::min(B::sub(B::min(B::min(at, B::adds(before, p1)), B::adds(after, p1)), base[i]), jump);
      const V l = B::add(m, c);
      B::store(cur[i] + kSlotFirst + k, l);
      least[i] = B::min(least[i], l);
      pair = B::add(pair, l);
    }
    sink(k, pair);
    if (kRowPath) {
      row_before = row_at;
      row_at = row_after;
    }
  }
  cur[0][0] = static_cast<std::uint8_t>(B::hmin(least[0]));
  cur[1][0] = static_cast<std::uint8_t>(B::hmin(least[1]));
}

// The downward pass's kN paths (2 or 4, the row path first) of one pixel.
// Two paths' sum fits a byte (at most 2 x 127), so with 4 paths in all
// it waits for the upward pass as bytes (pair_sum), half the memory
// traffic; four paths' sum needs the 16-bit sum.
template <class B, int kN>
inline void down_paths(const std::uint8_t* const* prev, std::uint8_t* const* cur, const std::uint8_t* cost,
                       std::int16_t* sum, std::uint8_t* pair_sum, int disparities, typename B::V p1,
                       typename B::V jump) noexcept {
  using V = typename B::V;
  using W = typename B::Wide;
  constexpr int kHalf = W::kLanes;  // a byte vector widens into two
  if (kN == 2) {
    update_path_pair<B, true>(prev, cur, cost, disparities, p1, jump, [pair_sum](int k, V pair) {
      B::store(pair_sum + k, pair);
    });
    return;
  }
  update_path_pair<B, true>(prev, cur, cost, disparities, p1, jump, [sum](int k, V pair) {
    W::store(sum + k, B::widen_lo(pair));
    W::store(sum + k + kHalf, B::widen_hi(pair));
  });
  // Loaded at the addresses and sizes just stored: forwarded from the store
  // buffer.
  update_path_pair<B, false>(prev + 2, cur + 2, cost, disparities, p1, jump, [sum](int k, V pair) {
    W::store(sum + k, W::add(W::load(sum + k), B::widen_lo(pair)));
    W::store(sum + k + kHalf, W::add(W::load(sum + k + kHalf), B::widen_hi(pair)));
  });
}

// The upward pass's kN paths of one pixel, added to the downward pass's
// sums (pair_sum with 2 paths a pass, sum with 4) into out.
template <class B, int kN>
inline void up_paths(const std::uint8_t* const* prev, std::uint8_t* const* cur, const std::uint8_t* cost,
                     const std::int16_t* sum, const std::uint8_t* pair_sum, std::int16_t* out, int disparities,
                     typename B::V p1, typename B::V jump) noexcept {
  using V = typename B::V;
  using W = typename B::Wide;
  constexpr int kHalf = W::kLanes;
  if (kN == 2) {
    update_path_pair<B, true>(prev, cur, cost, disparities, p1, jump, [pair_sum, out](int k, V pair) {
      const V down = B::load(pair_sum + k);
      W::store(out + k, W::add(B::widen_lo(down), B::widen_lo(pair)));
      W::store(out + k + kHalf, W::add(B::widen_hi(down), B::widen_hi(pair)));
    });
    return;
  }
  update_path_pair<B, true>(prev, cur, cost, disparities, p1, jump, [sum, out](int k, V pair) {
    W::store(out + k, W::add(W::load(sum + k), B::widen_lo(pair)));
    W::store(out + k + kHalf, W::add(W::load(sum + k + kHalf), B::widen_hi(pair)));
  });
  update_path_pair<B, false>(prev + 2, cur + 2, cost, disparities, p1, jump, [out](int k, V pair) {
    W::store(out + k, W::add(W::load(out + k), B::widen_lo(pair)));
    W::store(out + k + kHalf, W::add(W::load(out + k + kHalf), B::widen_hi(pair)));
  });
}

// Row y's matching costs into the cost volume, from the census planes.
template <class B, class Workspace>
inline void census_costs(Workspace& ws, int y, int w, int d) noexcept {
  const std::uint8_t* left_planes[kCensusPlanes];
  const std::uint8_t* right_planes[kCensusPlanes];
  for (int g = 0; g < kCensusPlanes; ++g) {
    left_planes[g] = ws.census_left[g].row(y);
    const std::uint8_t* r = ws.census_right[g].row(y);
    std::uint8_t* rev = ws.right_reversed.get() + static_cast<std::ptrdiff_t>(g) * ws.reversed_stride;
    for (int x = 0; x < w; ++x) rev[w - 1 - x] = r[x];
    right_planes[g] = rev;
  }
  cost_row<B>(left_planes, right_planes, w, d, ws.cost.get() + static_cast<std::ptrdiff_t>(y) * w * d);
}

// Both passes over a w x h image with d matched disparities (a multiple
// of B::kLanes), the winners into ws.disparity. ws: the matcher's
// workspace (semi_global_matcher.cpp).
template <class B, int kPaths, bool kFused, class Workspace>
inline void aggregate(Workspace& ws, const DisparityParams& params, int w, int h, int d) noexcept {
  constexpr int kN = kPaths / 2;  // paths per pass
  using W = typename B::Wide;
  const int slot = ws.slot;
  const typename B::V p1 = B::splat(static_cast<std::uint8_t>(params.p1));
  const typename B::V jump = B::splat(static_cast<std::uint8_t>(params.p2));
  const std::ptrdiff_t pixel = d, row_cells = static_cast<std::ptrdiff_t>(w) * d;
  // Direction j of a pass: 0 along the row, 1 along the column, 2 and 3
  // the diagonals; the column and diagonal paths keep their previous row.
  std::uint8_t* prev_row[3] = {ws.rows[0], ws.rows[1], ws.rows[2]};
  std::uint8_t* cur_row[3] = {ws.rows[3], ws.rows[4], ws.rows[5]};
  auto at = [slot](std::uint8_t* row, int x) { return row + static_cast<std::ptrdiff_t>(x) * slot; };

  const std::uint8_t* prev[4];
  std::uint8_t* cur[4];
  // With 4 paths the downward sums are bytes, in the first half of the
  // 16-bit volume's memory.
  std::uint8_t* pair_sums = reinterpret_cast<std::uint8_t*>(ws.sums.get());

  // Down: from the left, from above, from above left and above right. A
  // row's costs are computed just before it, so the pass finds them in cache.
  for (int y = 0; y < h; ++y) {
    census_costs<B>(ws, y, w, d);
    const std::uint8_t* cost = ws.cost.get() + y * row_cells;
    std::int16_t* sum = ws.sums.get() + y * row_cells;
    std::uint8_t* pair_sum = pair_sums + y * row_cells;
    for (int x = 0; x < w; ++x) {
      prev[0] = x > 0 ? ws.horizontal[(x - 1) & 1] : ws.zero;
      cur[0] = ws.horizontal[x & 1];
      prev[1] = y > 0 ? at(prev_row[0], x) : ws.zero;
      cur[1] = at(cur_row[0], x);
      if (kN == 4) {
        prev[2] = y > 0 && x > 0 ? at(prev_row[1], x - 1) : ws.zero;
        cur[2] = at(cur_row[1], x);
        prev[3] = y > 0 && x + 1 < w ? at(prev_row[2], x + 1) : ws.zero;
        cur[3] = at(cur_row[2], x);
      }
      down_paths<B, kN>(prev, cur, cost + x * pixel, sum + x * pixel, pair_sum + x * pixel, d, p1, jump);
    }
    std::swap(prev_row, cur_row);
  }

  // Up: from the right, from below, from below right and below left; each
  // pixel's sums are then complete and its disparity is chosen (fused:
  // from a one-pixel buffer in L1, PackedWinner; else from the volume,
  // row by row).
  const DisparityRowScratch scratch{ws.left_best.get(), ws.right_best.get(), ws.right_cost.get()};
  std::int16_t* total = ws.total.get();
  std::int16_t* row_sums = ws.row_sums.get();
  for (int y = h - 1; y >= 0; --y) {
    const std::uint8_t* cost = ws.cost.get() + y * row_cells;
    const std::int16_t* sum = ws.sums.get() + y * row_cells;
    const std::uint8_t* pair_sum = pair_sums + y * row_cells;
    std::int16_t* out = ws.disparity.row(y);
    PackedWinner<W> winner(w, d, params.uniqueness_percent, scratch.right_cost);
    for (int x = w - 1; x >= 0; --x) {
      prev[0] = x + 1 < w ? ws.horizontal[(x + 1) & 1] : ws.zero;
      cur[0] = ws.horizontal[x & 1];
      prev[1] = y + 1 < h ? at(prev_row[0], x) : ws.zero;
      cur[1] = at(cur_row[0], x);
      if (kN == 4) {
        prev[2] = y + 1 < h && x + 1 < w ? at(prev_row[1], x + 1) : ws.zero;
        cur[2] = at(cur_row[1], x);
        prev[3] = y + 1 < h && x > 0 ? at(prev_row[2], x - 1) : ws.zero;
        cur[3] = at(cur_row[2], x);
      }
      const std::int16_t* s = sum + x * pixel;
      const std::uint8_t* ps = pair_sum + x * pixel;
      if (kFused) {
        // The sums wait in a one-pixel buffer that stays in L1 rather than
        // in registers: the paths already use nearly all of them.
        up_paths<B, kN>(prev, cur, cost + x * pixel, s, ps, total, d, p1, jump);
        winner.begin(x);
        for (int k = 0; k < d; k += W::kLanes) winner.add(k, W::load(total + k));
        winner.finish(total, out + x, scratch.left_best + x);
      } else {
        up_paths<B, kN>(prev, cur, cost + x * pixel, s, ps, row_sums + x * pixel, d, p1, jump);
      }
    }
    std::swap(prev_row, cur_row);
    if (kFused) {
      winner.check_right(scratch.left_best, params.lr_max_diff, out);
    } else {
      select_disparity_row(row_sums, w, d, params.uniqueness_percent, params.lr_max_diff, scratch, out);
    }
  }
}

// aggregate() for the matcher's path count, fused (sums that pack with
// their disparity, packed_winner_fits) or not.
template <class B, class Workspace>
void aggregate_image(Workspace& ws, const DisparityParams& params, int w, int h, int d, bool fused) noexcept {
  if (params.paths == 8) {
    fused ? aggregate<B, 8, true>(ws, params, w, h, d) : aggregate<B, 8, false>(ws, params, w, h, d);
  } else {
    fused ? aggregate<B, 4, true>(ws, params, w, h, d) : aggregate<B, 4, false>(ws, params, w, h, d);
  }
}
