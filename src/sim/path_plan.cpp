#include "sim/path_plan.hpp"
#include "core/physical_constants.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rtfuse::sim {

namespace plan_detail {

double Piece::heading(double u) const noexcept {
  if (sinusoid) return psi0 + amp * (1.0 - std::cos(wave * u));
  return psi0 + u * (k0 + 0.5 * k1 * u);
}

double Piece::curvature(double u) const noexcept {
  if (sinusoid) return amp * wave * std::sin(wave * u);
  return k0 + k1 * u;
}

double Piece::curvature_slope(double u) const noexcept {
  if (sinusoid) return amp * wave * wave * std::cos(wave * u);
  return k1;
}

}  // namespace plan_detail

namespace {

using plan_detail::Phase;
using plan_detail::Piece;

constexpr double kKnotStep = 0.05;  // m; quadrature over at most this keeps 1e-12 m at 0.1 m radius
constexpr std::size_t kMaxKnots = std::size_t{1} << 21;  // ~100 km of path, 32 MB of knots
// A closed curve whose heading swings as A(1 - cos(2 pi s / S)) ends where it
// started iff J0(A) = 0; the first zero gives a figure eight (+-138 degrees
// about the mean heading, much like a lemniscate's +-135).
constexpr double kJ0FirstZero = 2.404825557695773;

// 5-point Gauss-Legendre on [-1, 1]: exact to degree 9.
constexpr double kGlX[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                            0.9061798459386640};
constexpr double kGlW[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                            0.2369268850561891};

// The displacement along a piece from u = a to u = b.
void integrate(const Piece& p, double a, double b, double* dx, double* dy) noexcept {
  const double half = 0.5 * (b - a);
  const double mid = 0.5 * (a + b);
  double sx = 0.0;
  double sy = 0.0;
  for (int i = 0; i < 5; ++i) {
    const double psi = p.heading(mid + half * kGlX[i]);
    sx += kGlW[i] * std::cos(psi);
    sy += kGlW[i] * std::sin(psi);
  }
  *dx = sx * half;
  *dy = sy * half;
}

double knot_u(const Piece& p, int i) noexcept { return i == p.knots - 1 ? p.length : i * kKnotStep; }

double sign_of(double v) noexcept { return v < 0.0 ? -1.0 : 1.0; }

double deg(double rad) noexcept { return rad * 180.0 / kPi; }

std::string format(const char* fmt, double a, double b = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

bool drives(SegmentType t) noexcept {
  return t == SegmentType::kStraight || t == SegmentType::kArc || t == SegmentType::kFigureEight;
}

// Curvature where a driving segment starts and ends: arcs keep theirs, the
// figure eight starts and ends at its crossing, where it is straight.
double body_curvature(const PathSegment& g) noexcept {
  return g.type == SegmentType::kArc ? sign_of(g.angle_rad) / g.radius_m : 0.0;
}

}  // namespace

class PlanBuilder {
 public:
  PlanBuilder(const DriveScenario& sc, PathPlan* out, PlanProblem* problem)
      : sc_(sc), out_(*out), problem_(*problem), accel_(sc.limits.max_accel_mps2),
        yaw_accel_(sc.limits.max_yaw_accel_rad_s2) {}

  bool build() {
    if (!(accel_ > 0.0) || !(yaw_accel_ > 0.0) || !std::isfinite(accel_) || !std::isfinite(yaw_accel_)) {
      return fail(-1, "the acceleration limits must be > 0 and finite");
    }
    std::vector<int> run;
    for (int i = 0; i < static_cast<int>(sc_.path.size()); ++i) {
      const PathSegment& g = sc_.path[static_cast<std::size_t>(i)];
      if (!valid(i, g)) return false;
      if (drives(g.type)) {
        run.push_back(i);
        continue;
      }
      if (!drive_run(run)) return false;
      run.clear();
      if (g.type == SegmentType::kSpin) {
        spin(g);
      } else {
        rest(g.duration_s);
      }
    }
    if (!drive_run(run)) return false;
    out_.end_time_ = t_;
    out_.length_ = s_;
    out_.final_heading_ = psi_;
    out_.final_ = PathPoint{x_, y_, psi_, 0.0, 0.0, 0.0, 0.0, s_};
    out_.phase_start_.reserve(out_.phases_.size());
    for (const Phase& ph : out_.phases_) out_.phase_start_.push_back(ph.t0);
    return true;
  }

 private:
  bool fail(int segment, std::string message) {
    problem_.segment = segment;
    problem_.message = std::move(message);
    return false;
  }

  // The loader checks every field; this keeps a hand-built scenario from
  // producing NaNs or endless plans.
  bool valid(int i, const PathSegment& g) {
    auto finite_positive = [](double v) { return v > 0.0 && std::isfinite(v); };
    switch (g.type) {
      case SegmentType::kStraight:
        if (!finite_positive(g.length_m) || !finite_positive(g.speed_mps)) {
          return fail(i, "length and speed must be > 0");
        }
        break;
      case SegmentType::kArc:
        if (!finite_positive(g.radius_m) || !finite_positive(g.speed_mps) || !(g.angle_rad != 0.0) ||
            !std::isfinite(g.angle_rad)) {
          return fail(i, "radius and speed must be > 0 and the angle non-zero");
        }
        break;
      case SegmentType::kFigureEight:
        if (!finite_positive(g.radius_m) || !finite_positive(g.speed_mps) || g.laps < 1) {
          return fail(i, "radius and speed must be > 0 and laps >= 1");
        }
        break;
      case SegmentType::kSpin:
        if (!finite_positive(g.yaw_rate_rad_s) || !(g.angle_rad != 0.0) || !std::isfinite(g.angle_rad)) {
          return fail(i, "the yaw rate must be > 0 and the angle non-zero");
        }
        break;
      case SegmentType::kStop:
        if (!finite_positive(g.duration_s)) return fail(i, "the duration must be > 0");
        break;
    }
    return true;
  }

  struct Draft {
    Piece piece;
    double cap = 0.0;  // cruise speed on it
  };

  // Consecutive driving segments: pieces with clothoids where the curvature
  // changes, then the speed profile from rest to rest over them.
  bool drive_run(const std::vector<int>& run) {
    if (run.empty()) return true;
    const std::size_t n = run.size();
    const auto seg = [&](std::size_t j) -> const PathSegment& { return sc_.path[static_cast<std::size_t>(run[j])]; };

    // A transition's turn counts towards the arcs next to it, so an arc
    // turns by exactly its angle and straights and figure eights keep their
    // exact length (the figure eight still closes).
    std::vector<double> transition_length(n, 0.0);  // [j]: between j and j + 1
    std::vector<double> arc_transition_yaw(n, 0.0);
    for (std::size_t j = 0; j + 1 < n; ++j) {
      const double ka = body_curvature(seg(j));
      const double kb = body_curvature(seg(j + 1));
      if (ka == kb) continue;
      const double v = std::min(seg(j).speed_mps, seg(j + 1).speed_mps);
      // At speed v a clothoid of sharpness c makes the yaw acceleration v^2 c.
      const double len = std::abs(kb - ka) * v * v / yaw_accel_;
      transition_length[j] = len;
      const bool arc_a = seg(j).type == SegmentType::kArc;
      const bool arc_b = seg(j + 1).type == SegmentType::kArc;
      if (arc_a && arc_b) {
        arc_transition_yaw[j] += len * (3.0 * ka + kb) / 8.0;
        arc_transition_yaw[j + 1] += len * (ka + 3.0 * kb) / 8.0;
      } else if (arc_a) {
        arc_transition_yaw[j] += 0.5 * len * (ka + kb);
      } else {
        arc_transition_yaw[j + 1] += 0.5 * len * (ka + kb);
      }
    }

    std::vector<Draft> drafts;
    for (std::size_t j = 0; j < n; ++j) {
      const PathSegment& g = seg(j);
      Draft d;
      d.cap = g.speed_mps;
      switch (g.type) {
        case SegmentType::kStraight: d.piece.length = g.length_m; break;
        case SegmentType::kArc: {
          const double k = body_curvature(g);
          const double body_yaw = g.angle_rad - arc_transition_yaw[j];
          if (body_yaw * k < 0.0 && std::abs(body_yaw) > 1e-12) {
            return fail(run[j], format("its curvature transitions alone turn the robot by %.1f deg at these speeds; "
                                       "make |angle_deg| larger than that, lower speed_mps here or next to it, "
                                       "or raise [limits] max_yaw_accel_dps2",
                                       deg(std::abs(arc_transition_yaw[j]))));
          }
          d.piece.k0 = k;
          d.piece.length = std::max(body_yaw / k, 0.0);
          break;
        }
        default: {  // figure eight
          const double lap = 2.0 * kPi * kJ0FirstZero * g.radius_m;  // tightest radius at the lobes' tips
          d.piece.sinusoid = true;
          d.piece.amp = g.right_first ? -kJ0FirstZero : kJ0FirstZero;
          d.piece.wave = 2.0 * kPi / lap;
          d.piece.length = lap * g.laps;
          break;
        }
      }
      if (d.piece.length > 0.0) drafts.push_back(d);
      if (transition_length[j] > 0.0) {
        Draft t;
        const double ka = body_curvature(g);
        const double kb = body_curvature(seg(j + 1));
        t.piece.length = transition_length[j];
        t.piece.k0 = ka;
        t.piece.k1 = (kb - ka) / transition_length[j];
        t.cap = std::min(g.speed_mps, seg(j + 1).speed_mps);
        drafts.push_back(t);
      }
    }

    // Boundary speeds: rest at both ends, a piece's cap on either side of a
    // boundary, then what braking (backward) and accelerating (forward)
    // within max_accel allow.
    const std::size_t m = drafts.size();
    std::vector<double> b(m + 1, 0.0);
    for (std::size_t i = 1; i < m; ++i) b[i] = std::min(drafts[i - 1].cap, drafts[i].cap);
    for (std::size_t i = m; i-- > 0;) {
      b[i] = std::min(b[i], std::sqrt(b[i + 1] * b[i + 1] + 2.0 * accel_ * drafts[i].piece.length));
    }
    for (std::size_t i = 0; i < m; ++i) {
      b[i + 1] = std::min(b[i + 1], std::sqrt(b[i] * b[i] + 2.0 * accel_ * drafts[i].piece.length));
    }

    for (std::size_t i = 0; i < m; ++i) {
      if (!emit_piece(drafts[i].piece)) return false;
      move(static_cast<int>(out_.pieces_.size()) - 1, drafts[i].cap, b[i], b[i + 1]);
    }
    return true;
  }

  // Places the piece at the current pose and integrates its knots.
  bool emit_piece(Piece p) {
    p.s0 = s_;
    p.x0 = x_;
    p.y0 = y_;
    p.psi0 = psi_;
    p.knot0 = static_cast<int>(out_.knot_x_.size());
    p.knots = static_cast<int>(std::ceil(p.length / kKnotStep)) + 1;
    if (out_.knot_x_.size() + static_cast<std::size_t>(p.knots) > kMaxKnots) {
      return fail(-1, format("the path is longer than %.0f km; split the drive into several scenarios",
                             kMaxKnots * kKnotStep / 1000.0));
    }
    double x = x_;
    double y = y_;
    out_.knot_x_.push_back(x);
    out_.knot_y_.push_back(y);
    for (int i = 0; i + 1 < p.knots; ++i) {
      double dx = 0.0;
      double dy = 0.0;
      integrate(p, knot_u(p, i), knot_u(p, i + 1), &dx, &dy);
      x += dx;
      y += dy;
      out_.knot_x_.push_back(x);
      out_.knot_y_.push_back(y);
    }
    const double tightest = p.sinusoid ? std::abs(p.amp * p.wave)
                                       : std::max(std::abs(p.k0), std::abs(p.k0 + p.k1 * p.length));
    out_.max_curvature_ = std::max(out_.max_curvature_, tightest);
    x_ = x;
    y_ = y;
    psi_ = p.heading(p.length);
    s_ += p.length;
    out_.pieces_.push_back(p);
    return true;
  }

  void add(Phase ph) {
    if (!(ph.duration > 0.0)) return;
    ph.t0 = t_;
    t_ += ph.duration;
    out_.phases_.push_back(ph);
  }

  // Along one piece from speed u to speed w, as fast as the cap and
  // max_accel allow: accelerate, cruise, brake.
  void move(int piece, double cap, double u, double w) {
    const double len = out_.pieces_[static_cast<std::size_t>(piece)].length;
    double peak = std::min(cap, std::sqrt((2.0 * accel_ * len + u * u + w * w) / 2.0));
    peak = std::max(peak, std::max(u, w));  // the passes guarantee it up to rounding
    const double d_acc = (peak * peak - u * u) / (2.0 * accel_);
    const double d_dec = (peak * peak - w * w) / (2.0 * accel_);
    const double d_cruise = std::max(len - d_acc - d_dec, 0.0);
    Phase ph;
    ph.kind = Phase::Kind::kMove;
    ph.piece = piece;
    ph.u0 = 0.0;
    ph.v0 = u;
    ph.a = accel_;
    ph.duration = (peak - u) / accel_;
    add(ph);
    ph.u0 = d_acc;
    ph.v0 = peak;
    ph.a = 0.0;
    ph.duration = peak > 0.0 ? d_cruise / peak : 0.0;
    add(ph);
    ph.u0 = d_acc + d_cruise;
    ph.a = -accel_;
    ph.duration = (peak - w) / accel_;
    add(ph);
  }

  // In place: yaw rate up at max_yaw_accel, cruise, down to rest.
  void spin(const PathSegment& g) {
    const double dir = sign_of(g.angle_rad);
    const double angle = std::abs(g.angle_rad);
    const double peak = std::min(g.yaw_rate_rad_s, std::sqrt(yaw_accel_ * angle));
    const double ramp_angle = peak * peak / (2.0 * yaw_accel_);
    const double cruise_angle = std::max(angle - 2.0 * ramp_angle, 0.0);
    const double start = psi_;
    Phase ph;
    ph.kind = Phase::Kind::kTurn;
    ph.x = x_;
    ph.y = y_;
    ph.s = s_;
    ph.psi0 = start;
    ph.alpha = dir * yaw_accel_;
    ph.duration = peak / yaw_accel_;
    add(ph);
    ph.psi0 = start + dir * ramp_angle;
    ph.w0 = dir * peak;
    ph.alpha = 0.0;
    ph.duration = cruise_angle / peak;
    add(ph);
    ph.psi0 = start + dir * (ramp_angle + cruise_angle);
    ph.alpha = -dir * yaw_accel_;
    ph.duration = peak / yaw_accel_;
    add(ph);
    psi_ = start + g.angle_rad;
  }

  void rest(double duration) {
    Phase ph;
    ph.kind = Phase::Kind::kRest;
    ph.x = x_;
    ph.y = y_;
    ph.s = s_;
    ph.psi0 = psi_;
    ph.duration = duration;
    add(ph);
  }

  const DriveScenario& sc_;
  PathPlan& out_;
  PlanProblem& problem_;
  double accel_;
  double yaw_accel_;
  double t_ = 0.0, s_ = 0.0, x_ = 0.0, y_ = 0.0, psi_ = 0.0;
};

bool PathPlan::build(const DriveScenario& scenario, PathPlan* out, PlanProblem* problem) {
  PlanProblem ignored;
  PathPlan plan;
  if (!PlanBuilder(scenario, &plan, problem != nullptr ? problem : &ignored).build()) {
    if (out != nullptr) *out = PathPlan();
    return false;
  }
  if (out != nullptr) *out = std::move(plan);
  return true;
}

std::pair<double, double> PathPlan::position(const Piece& p, double u) const noexcept {
  const auto k0 = static_cast<std::size_t>(p.knot0);
  if (p.knots < 2) return {knot_x_[k0], knot_y_[k0]};
  const int k = std::clamp(static_cast<int>(u / kKnotStep), 0, p.knots - 2);
  double dx = 0.0;
  double dy = 0.0;
  integrate(p, knot_u(p, k), u, &dx, &dy);
  return {knot_x_[k0 + static_cast<std::size_t>(k)] + dx, knot_y_[k0 + static_cast<std::size_t>(k)] + dy};
}

PathPoint PathPlan::at(double t) const noexcept {
  if (!(t > 0.0) || phases_.empty()) {
    // Before the start (and for NaN): at rest where it starts.
    return phases_.empty() ? final_ : PathPoint{};
  }
  if (t >= end_time_) return final_;
  const auto it = std::upper_bound(phase_start_.begin(), phase_start_.end(), t);
  const std::size_t i = it == phase_start_.begin() ? 0 : static_cast<std::size_t>(it - phase_start_.begin()) - 1;
  const Phase& ph = phases_[i];
  const double tau = std::clamp(t - ph.t0, 0.0, ph.duration);
  PathPoint p;
  switch (ph.kind) {
    case Phase::Kind::kMove: {
      const Piece& pc = pieces_[static_cast<std::size_t>(ph.piece)];
      const double u = std::clamp(ph.u0 + tau * (ph.v0 + 0.5 * ph.a * tau), 0.0, pc.length);
      const double v = std::max(ph.v0 + ph.a * tau, 0.0);
      const double k = pc.curvature(u);
      const auto xy = position(pc, u);
      p.x = xy.first;
      p.y = xy.second;
      p.heading = pc.heading(u);
      p.speed = v;
      p.yaw_rate = k * v;
      p.accel = ph.a;
      p.yaw_accel = pc.curvature_slope(u) * v * v + k * ph.a;
      p.distance = pc.s0 + u;
      break;
    }
    case Phase::Kind::kTurn:
    case Phase::Kind::kRest:
      p.x = ph.x;
      p.y = ph.y;
      p.distance = ph.s;
      p.heading = ph.psi0 + tau * (ph.w0 + 0.5 * ph.alpha * tau);
      p.yaw_rate = ph.w0 + ph.alpha * tau;
      p.yaw_accel = ph.alpha;
      break;
  }
  return p;
}

}  // namespace rtfuse::sim
