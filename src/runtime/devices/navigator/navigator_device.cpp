#include "runtime/devices/navigator/navigator_device.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "navigation/path_clearance.hpp"
#include "navigation/path_smoother.hpp"
#include "navigation/speckle_filter.hpp"

namespace rtfuse {

// goals: goal messages taken (rejected: of those, refused here or by the
// planner: NaN, another frame, outside the map, in an obstacle); plans:
// paths searched on the navigator's thread (failures: none found);
// replans_*: why a goal was planned again (the map blocked the path, the
// robot left it, a new grid after a failure); late: grids the navigator
// took after their time had passed (live only; a replay may then differ);
// inputs_dropped: goals or stops a full ring refused; inputs_bad: stops
// that did not decode; lost: estimates, requests or results a full ring
// refused; speckles: lone obstacle cells the last grid had (drop_speckles).
const char* const kNavigatorKeys[19] = {"goals",       "rejected",       "reached",     "plans",     "plan_failures",
                                        "replans_blocked", "replans_off_path", "replans_map", "expansions", "plan_us",
                                        "max_plan_us", "grids",          "grids_dropped", "costmap_us", "late",
                                        "inputs_dropped", "inputs_bad",   "lost",        "speckles"};

namespace {

constexpr TimeNs kNavigatorIdleNs = 5'000'000;
// Ticks of a 1 kHz loop for 8 s: the navigator's thread may be busy with a
// long plan meanwhile.
constexpr int kNavigatorPoseRing = 8192;
constexpr TimeNs kNever = std::numeric_limits<TimeNs>::max();

TimeNs nav_seconds_ns(double s) { return static_cast<TimeNs>(std::llround(s * 1e9)); }

// The cell of a coordinate; far outside the grid stays far outside
// without overflowing an int.
int cell_of(double v, double origin, double resolution) noexcept {
  const double c = std::floor((v - origin) / resolution);
  return static_cast<int>(std::clamp(c, -1e9, 1e9));
}

void set_goal_error(NavSnapshot& n, const char* text) noexcept {
  std::strncpy(n.goal_error, text, sizeof n.goal_error - 1);
  n.goal_error[sizeof n.goal_error - 1] = '\0';
}

bool rejects_goal(navigation::PlanStatus s) noexcept {
  return s == navigation::PlanStatus::kGoalOutsideGrid || s == navigation::PlanStatus::kGoalInObstacle ||
         s == navigation::PlanStatus::kGoalUnknown;
}

}  // namespace

NavigatorDevice::NavigatorDevice(int slot) : slot_(slot), poses_(kNavigatorPoseRing) {}

NavigatorDevice::~NavigatorDevice() = default;

std::unique_ptr<NavigatorDevice> NavigatorDevice::create(GridSource& mapper, FusionCore& core, int slot,
                                                         std::string* error) {
  const RuntimeConfig& cfg = core.config();
  const NavigationSection& n = cfg.hardware.navigation;
  std::unique_ptr<NavigatorDevice> d(new NavigatorDevice(slot));
  d->config_ = n;
  d->world_frame_ = std::string(cfg.world_frame.view());
  d->layout_ = mapper.grid_layout();
  const GridLayout& g = d->layout_;
  if (g.width <= 0 || g.height <= 0 || !(g.resolution_m > 0.0)) {
    *error = "[navigation]: the mapper makes no grid to plan on (mapping.grid_rate = 0?)";
    return nullptr;
  }
  d->map_delay_ns_ = nav_seconds_ns(n.map_delay_s);
  d->plan_delay_ns_ = nav_seconds_ns(n.plan_delay_s);
  d->command_period_ns_ = nav_seconds_ns(1.0 / n.follower.command_rate_hz);
  if (n.map_delay_s <= cfg.hardware.mapping.pose_delay_s) {
    *error = "[navigation]: map_delay (" + std::to_string(n.map_delay_s) + " s) must exceed mapping.pose_delay (" +
             std::to_string(cfg.hardware.mapping.pose_delay_s) + " s): a grid cannot be planned on before it is made";
    return nullptr;
  }
  // A path crosses the grid a few times at most; longer ones are refused
  // by the planner (kPathTooLong), not truncated.
  d->max_points_ = static_cast<int>(std::min<long long>(8LL * (g.width + g.height), 1 << 20));
  navigation::CostmapParams cp;
  cp.resolution_m = g.resolution_m;
  cp.inscribed_radius_m = n.inscribed_radius_m;
  cp.inflation_radius_m = n.inflation_radius_m;
  cp.cost_scaling_factor = n.cost_scaling_factor;
  cp.unknown = n.unknown_free ? navigation::UnknownCells::kFree : navigation::UnknownCells::kNoInformation;
  try {
    d->costmap_ = std::make_unique<navigation::Costmap>(g.width, g.height, cp);
    d->planner_ = std::make_unique<navigation::GridPlanner>(g.width, g.height, static_cast<std::size_t>(d->max_points_));
    d->follower_ = std::make_unique<navigation::PathFollower>(n.follower, d->max_points_);
    d->gate_ = std::make_unique<navigation::CommandGate>(n.follower);
  } catch (const std::exception& e) {
    *error = std::string("[navigation]: ") + e.what();
    return nullptr;
  }
  const std::size_t cells = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  {
    // Nothing seen yet: every cell unknown, as the mapper's first grid.
    std::unique_ptr<std::int8_t[]> unknown(new std::int8_t[cells]);
    std::fill(unknown.get(), unknown.get() + cells, std::int8_t{-1});
    d->costmap_->set_grid(unknown.get());
  }
  d->planner_params_.passability.lethal_from = static_cast<std::uint8_t>(n.follower.lethal_from);
  d->planner_params_.passability.unknown_passable = n.unknown_free;
  d->planner_params_.cost_weight = n.cost_weight;
  for (int i = 0; i < kGridSlots; ++i) {
    d->grid_slots_[i].reset(new std::int8_t[cells]);
    d->free_grids_.try_push(i);
  }
  for (int i = 0; i < kPathSlots; ++i) {
    d->path_slots_[i].reset(new navigation::Point2[static_cast<std::size_t>(d->max_points_)]);
    d->free_paths_.try_push(i);
  }
  d->path_.reset(new navigation::Point2[static_cast<std::size_t>(d->max_points_)]);
  d->smoothed_.reset(new navigation::GridCell[static_cast<std::size_t>(d->max_points_)]);
  if (n.drop_speckles) d->filtered_.reset(new std::int8_t[cells]);
  for (int i = 0; i < 3; ++i) {
    d->display_.buffer(i).points.reset(new transport::PathPoint2[static_cast<std::size_t>(d->max_points_)]);
  }
  d->path_encoder_ = transport::PathEncoder::create(d->max_points_, d->world_frame_, error);
  if (!d->path_encoder_) {
    *error = "[navigation]: " + *error;
    return nullptr;
  }
  d->nav_.active = true;
  d->health_.store(d->stats_);
  return d;
}

// --- LCM thread ----------------------------------------------------------------

void NavigatorDevice::on_input(int channel, const std::uint8_t* data, int size, TimeNs now) noexcept {
  (void)now;
  if (channel == kGoalInput) {
    GoalInput in;
    const transport::DecodeResult r = decoder_.decode_goal(data, size, &in.goal);
    in.error = r == transport::DecodeResult::kOk ? 0 : static_cast<int>(r);
    in.frame_ok = r == transport::DecodeResult::kOk && decoder_.goal_frame() == world_frame_;
    if (!goals_.try_push(in)) inputs_dropped_.fetch_add(1, std::memory_order_relaxed);
  } else if (channel == kStopInput) {
    transport::NavStop stop;
    if (decoder_.decode_stop(data, size, &stop) != transport::DecodeResult::kOk) {
      // An undecodable stop still stops: whoever sent it meant something.
      inputs_bad_.fetch_add(1, std::memory_order_relaxed);
      stop.stop = true;
    }
    if (!stops_.try_push(StopInput{stop.stop})) inputs_dropped_.fetch_add(1, std::memory_order_relaxed);
  }
}

// --- mapper thread -------------------------------------------------------------

void NavigatorDevice::on_grid(const std::int8_t* cells, TimeNs stamp) noexcept {
  int slot = spare_grid_;
  spare_grid_ = -1;
  if (slot < 0 && !free_grids_.try_pop(slot)) {
    grids_dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  std::memcpy(grid_slots_[slot].get(), cells,
              static_cast<std::size_t>(layout_.width) * static_cast<std::size_t>(layout_.height));
  if (!grid_notes_.try_push(GridNote{stamp, slot})) {
    // Kept on this side: the free ring has one producer, the navigator.
    spare_grid_ = slot;
    grids_dropped_.fetch_add(1, std::memory_order_relaxed);
  }
}

void NavigatorDevice::on_map_current(TimeNs stamp) noexcept {
  if (!grid_notes_.try_push(GridNote{stamp, -1})) grids_dropped_.fetch_add(1, std::memory_order_relaxed);
}

// --- loop thread ---------------------------------------------------------------

void NavigatorDevice::request(const Request& r) noexcept {
  if (!requests_.try_push(r)) lost_.fetch_add(1, std::memory_order_relaxed);
}

void NavigatorDevice::reject_goal(const char* why) noexcept {
  ++goals_rejected_;
  nav_.goal_state = GoalState::kRejected;
  set_goal_error(nav_, why);
  goal_active_loop_ = false;
  have_path_ = false;
  blocked_ = false;
  follower_->clear_path();
}

void NavigatorDevice::take_inputs(const Snapshot& s, TimeNs now) noexcept {
  StopInput st;
  while (stops_.try_pop(st)) {
    ++stops_taken_;
    stop_latched_ = st.stop;
  }
  GoalInput g;
  while (goals_.try_pop(g)) {
    ++goals_taken_;
    ++nav_.goal_seq;
    // A new goal, good or bad, replaces the one before: the robot never
    // goes on to a goal its operator has already changed.
    if (goal_active_loop_) request(Request{now, navigator_detail::RequestKind::kDone, nav_.goal_seq - 1, 0, 0, {}});
    nav_.goal_x = g.goal.x;
    nav_.goal_y = g.goal.y;
    stop_latched_ = false;
    if (g.error != 0) {
      reject_goal(transport::to_string(static_cast<transport::DecodeResult>(g.error)));
      continue;
    }
    if (!g.frame_ok) {
      reject_goal("goal in another frame than the map's");
      continue;
    }
    if (!navigation::usable(navigation::Point2{g.goal.x, g.goal.y})) {
      reject_goal("goal farther than 1000 km");
      continue;
    }
    nav_.goal_state = GoalState::kActive;
    set_goal_error(nav_, "");
    goal_active_loop_ = true;
    have_path_ = false;
    blocked_ = false;
    off_path_asked_ = -1;
    follower_->clear_path();
    Request r;
    r.tick = now;
    r.kind = navigator_detail::RequestKind::kGoal;
    r.goal_seq = nav_.goal_seq;
    r.goal_x = g.goal.x;
    r.goal_y = g.goal.y;
    r.start = LoopPose{now, s.initialized, s.state[0], s.state[1], s.state[5]};
    r.start.ok = s.initialized && navigation::usable(navigation::Pose2{s.state[0], s.state[1], s.state[5]});
    request(r);
  }
}

void NavigatorDevice::adopt_results(TimeNs now) noexcept {
  for (const Result* p = results_.peek(); p != nullptr && p->apply_at <= now; p = results_.peek()) {
    const Result r = *p;
    results_.pop();
    if (r.map_stamp > loop_map_stamp_) loop_map_stamp_ = r.map_stamp;
    if (r.cause != PlanCause::kNone && goal_active_loop_ && r.goal_seq == nav_.goal_seq) {
      if (r.status == navigation::PlanStatus::kOk && r.slot >= 0 &&
          follower_->set_path(path_slots_[r.slot].get(), r.points)) {
        have_path_ = true;
        blocked_ = false;
        off_path_asked_ = -1;
        ++nav_.plan_seq;
        nav_.path_points = r.points;
        set_goal_error(nav_, "");
      } else if (rejects_goal(r.status)) {
        reject_goal(navigation::to_string(r.status));
        request(Request{now, navigator_detail::RequestKind::kDone, r.goal_seq, 0, 0, {}});
      } else if (r.blocked) {
        blocked_ = true;
        set_goal_error(nav_, navigation::to_string(r.status));
      } else {
        have_path_ = false;
        follower_->clear_path();
        set_goal_error(nav_, r.status == navigation::PlanStatus::kOk ? "path refused by the follower"
                                                                      : navigation::to_string(r.status));
      }
      if (r.cause == PlanCause::kOffPath) off_path_asked_ = -1;
    }
    if (r.slot >= 0) free_paths_.try_push(r.slot);
  }
}

void NavigatorDevice::command(Snapshot& s, TimeNs now) noexcept {
  nav_.command_due = false;
  if (any_command_ && now < next_command_) return;
  // Due times a period apart on tick time, so 20 Hz is 20 Hz whatever the
  // loop's rate, and a replay sends at the same ticks.
  next_command_ = any_command_ ? next_command_ + command_period_ns_ : now + command_period_ns_;
  if (next_command_ <= now) next_command_ = now + command_period_ns_;
  any_command_ = true;

  const navigation::Pose2 pose{s.state[0], s.state[1], s.state[5]};
  const bool estimate_ok = s.initialized && navigation::usable(pose);
  navigation::FollowResult fr;
  if (have_path_ && estimate_ok) fr = follower_->follow(pose, gate_->last_command().linear);
  if (have_path_ && goal_active_loop_ && !fr.reached() && fr.cross_track_m > config_.off_path_m &&
      off_path_asked_ < 0) {
    off_path_asked_ = now;
    ++replans_off_path_;
    Request r;
    r.tick = now;
    r.kind = navigator_detail::RequestKind::kOffPath;
    r.goal_seq = nav_.goal_seq;
    r.start = LoopPose{now, true, pose.x, pose.y, pose.yaw};
    request(r);
  }
  if (fr.reached() && goal_active_loop_) {
    goal_active_loop_ = false;
    ++reached_;
    nav_.goal_state = GoalState::kReached;
    request(Request{now, navigator_detail::RequestKind::kDone, nav_.goal_seq, 0, 0, {}});
  }
  const bool reached = nav_.goal_state == GoalState::kReached;
  navigation::GateInput in;
  in.now = now;
  in.enabled = config_.follow;
  in.have_goal = goal_active_loop_ || reached;
  in.have_path = have_path_;
  in.goal_reached = reached;
  in.stop_requested = stop_latched_;
  in.estimate_stamp = s.stamp_ns;
  in.estimate_finite = estimate_ok;
  in.map_stamp = loop_map_stamp_;
  in.path_blocked = blocked_;
  const navigation::GateOutput out = gate_->step(in, fr.command);
  ++commands_;
  nav_.command_due = true;
  nav_.send_command = config_.follow || goal_active_loop_;
  nav_.linear_mps = out.command.linear;
  nav_.angular_rps = out.command.angular;
  nav_.stop_reason = static_cast<std::uint8_t>(out.reason);
  nav_.remaining_m = have_path_ ? fr.remaining_m : 0.0;
  nav_.cross_track_m = have_path_ ? fr.cross_track_m : 0.0;
}

void NavigatorDevice::fill_snapshot(Snapshot& s) noexcept {
  const TimeNs now = s.tick_time_ns;
  LoopPose p{now, false, s.state[0], s.state[1], s.state[5]};
  p.ok = s.initialized && navigation::usable(navigation::Pose2{p.x, p.y, p.yaw});
  if (!poses_.try_push(p)) lost_.fetch_add(1, std::memory_order_relaxed);
  take_inputs(s, now);
  adopt_results(now);
  command(s, now);
  // Last: everything this tick asked of the navigator's thread is in its
  // rings before it may work up to this tick.
  loop_tick_.store(now, std::memory_order_release);

  navigator_detail::NavStats v;
  health_.load(v);
  nav_.plans = v.plans;
  nav_.plan_failures = v.plan_failures;
  nav_.replans_blocked = v.replans_blocked;
  nav_.replans_off_path = replans_off_path_;
  s.nav = nav_;
  if (slot_ < 0) return;
  DeviceStatus& d = s.devices[slot_];
  set_device_values(d, kNavigatorKeys,
                    {goals_taken_, goals_rejected_, reached_, v.plans, v.plan_failures, v.replans_blocked, replans_off_path_,
                     v.replans_map, v.expansions, v.plan_ns / 1000, v.max_plan_ns / 1000, v.grids,
                     grids_dropped_.load(std::memory_order_relaxed), v.costmap_ns / 1000, v.late,
                     inputs_dropped_.load(std::memory_order_relaxed), inputs_bad_.load(std::memory_order_relaxed),
                     lost_.load(std::memory_order_relaxed), v.speckles});
  const navigation::StopReason reason = static_cast<navigation::StopReason>(nav_.stop_reason);
  d.state = navigation::to_string(reason);
  set_device_message(d.message, nav_.goal_error);
  switch (reason) {
    case navigation::StopReason::kNone:
    case navigation::StopReason::kNoGoal:
    case navigation::StopReason::kGoalReached:
    case navigation::StopReason::kDisabled:
      d.level = nav_.goal_state == GoalState::kRejected ? DeviceLevel::kWarn : DeviceLevel::kOk;
      break;
    case navigation::StopReason::kBadCommand: d.level = DeviceLevel::kError; break;
    default: d.level = DeviceLevel::kWarn; break;
  }
}

// --- navigator thread ----------------------------------------------------------

void NavigatorDevice::advance_poses(TimeNs t) noexcept {
  for (const LoopPose* p = poses_.peek(); p != nullptr && p->tick <= t; p = poses_.peek()) {
    pose_ = *p;
    poses_.pop();
  }
}

void NavigatorDevice::send(Result r) noexcept {
  r.apply_at = r.time + plan_delay_ns_;
  if (!results_.try_push(r)) {
    lost_.fetch_add(1, std::memory_order_relaxed);
    // Kept on this side: the free ring has one producer, the loop.
    if (r.slot >= 0) spare_path_ = r.slot;
  }
}

bool NavigatorDevice::remaining_path_blocked() const noexcept {
  if (path_size_ < 1) return false;
  int nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < path_size_; ++i) {
    const double dx = path_[i].x - pose_.x;
    const double dy = path_[i].y - pose_.y;
    const double d2 = dx * dx + dy * dy;
    if (d2 < best) {
      best = d2;
      nearest = i;
    }
  }
  const navigation::GridGeometry geometry{layout_.origin_x, layout_.origin_y, layout_.resolution_m};
  return navigation::path_blocked(costmap_->view(), geometry, path_.get(), path_size_, nearest, path_[nearest],
                                  std::numeric_limits<double>::infinity(), planner_params_.passability.lethal_from);
}

void NavigatorDevice::plan_and_send(TimeNs t, const LoopPose& from, PlanCause cause) noexcept {
  Result res;
  res.time = t;
  res.map_stamp = map_stamp_;
  res.goal_seq = goal_seq_;
  res.cause = cause;
  if (!from.ok) {
    res.status = navigation::PlanStatus::kInvalidInput;
    ++stats_.plan_failures;
    send(res);
    return;
  }
  const double ox = layout_.origin_x;
  const double oy = layout_.origin_y;
  const double r = layout_.resolution_m;
  const navigation::GridCell start{cell_of(from.x, ox, r), cell_of(from.y, oy, r)};
  const navigation::GridCell goal{cell_of(goal_x_, ox, r), cell_of(goal_y_, oy, r)};
  const TimeNs t0 = monotonic_now_ns();
  navigation::PlanResult pr = planner_->plan(costmap_->view(), start, goal, planner_params_);
  const TimeNs t1 = monotonic_now_ns();
  ++stats_.plans;
  stats_.expansions = static_cast<std::int64_t>(pr.expansions);
  stats_.plan_ns = t1 - t0;
  stats_.max_plan_ns = std::max(stats_.max_plan_ns, t1 - t0);
  res.status = pr.status;
  int slot = -1;
  if (pr.ok() && spare_path_ >= 0) {
    slot = spare_path_;
    spare_path_ = -1;
  } else if (pr.ok() && !free_paths_.try_pop(slot)) {
    // Every path slot is waiting for the loop: it has stopped taking
    // results, so this one would not be taken either.
    res.status = navigation::PlanStatus::kPathTooLong;
    lost_.fetch_add(1, std::memory_order_relaxed);
  }
  if (res.status != navigation::PlanStatus::kOk) {
    ++stats_.plan_failures;
    res.blocked = cause == PlanCause::kBlocked;
    if (!res.blocked) path_ok_ = false;
    send(res);
    return;
  }
  navigation::Point2* pts = path_slots_[slot].get();
  const navigation::GridCell* cells = pr.path;
  std::size_t count = pr.path_cells;
  if (config_.smooth_cost > 0) {
    navigation::Passability margin = planner_params_.passability;
    margin.lethal_from = static_cast<std::uint8_t>(std::min<int>(config_.smooth_cost, margin.lethal_from));
    count = navigation::smooth_path(costmap_->view(), margin, pr.path, pr.path_cells, smoothed_.get());
    cells = smoothed_.get();
  }
  const int n = static_cast<int>(count);
  for (int i = 0; i < n; ++i) {
    pts[i] = navigation::Point2{ox + (cells[i].x + 0.5) * r, oy + (cells[i].y + 0.5) * r};
  }
  std::copy(pts, pts + n, path_.get());
  path_size_ = n;
  path_ok_ = true;
  res.slot = slot;
  res.points = n;
  res.cost = pr.cost;
  navigator_detail::PathForDisplay& shown = display_.write_buffer();
  for (int i = 0; i < n; ++i) shown.points[i] = transport::PathPoint2{pts[i].x, pts[i].y};
  shown.count = n;
  shown.goal_seq = goal_seq_;
  shown.cost = pr.cost;
  shown.stamp = t;
  display_.publish();
  send(res);
}

void NavigatorDevice::apply_grid(const GridNote& note, TimeNs t) noexcept {
  if (note.stamp > map_stamp_) map_stamp_ = note.stamp;
  if (note.slot < 0) {
    send(Result{t, 0, map_stamp_, goal_seq_, PlanCause::kNone});
    return;
  }
  const TimeNs t0 = monotonic_now_ns();
  const std::int8_t* grid = grid_slots_[note.slot].get();
  if (filtered_) {
    stats_.speckles = static_cast<std::int64_t>(navigation::drop_speckles(
        grid, filtered_.get(), layout_.width, layout_.height, costmap_->params().occupied_from));
    grid = filtered_.get();
  }
  costmap_->update(grid);
  stats_.costmap_ns = monotonic_now_ns() - t0;
  ++stats_.grids;
  free_grids_.try_push(note.slot);
  if (goal_active_) {
    if (!path_ok_) {
      ++stats_.replans_map;
      plan_and_send(t, pose_, PlanCause::kMapChanged);
      return;
    }
    if (remaining_path_blocked()) {
      ++stats_.replans_blocked;
      plan_and_send(t, pose_, PlanCause::kBlocked);
      return;
    }
  }
  send(Result{t, 0, map_stamp_, goal_seq_, PlanCause::kNone});
}

void NavigatorDevice::apply_request(const Request& r) noexcept {
  switch (r.kind) {
    case navigator_detail::RequestKind::kGoal:
      goal_active_ = true;
      goal_seq_ = r.goal_seq;
      goal_x_ = r.goal_x;
      goal_y_ = r.goal_y;
      path_ok_ = false;
      path_size_ = 0;
      plan_and_send(r.tick, r.start, PlanCause::kGoal);
      break;
    case navigator_detail::RequestKind::kOffPath:
      if (goal_active_ && r.goal_seq == goal_seq_) plan_and_send(r.tick, r.start, PlanCause::kOffPath);
      break;
    case navigator_detail::RequestKind::kDone:
      if (r.goal_seq == goal_seq_) {
        goal_active_ = false;
        path_ok_ = false;
        path_size_ = 0;
      }
      break;
  }
}

void NavigatorDevice::step(TimeNs timeout_ns) noexcept {
  const TimeNs limit = loop_tick_.load(std::memory_order_acquire);
  bool worked = false;
  for (;;) {
    const Request* rq = requests_.peek();
    const GridNote* gn = grid_notes_.peek();
    const TimeNs tr = rq != nullptr ? rq->tick : kNever;
    const TimeNs tg = gn != nullptr ? gn->stamp + map_delay_ns_ : kNever;
    const TimeNs t = std::min(tr, tg);
    if (t == kNever || t > limit) break;
    advance_poses(t);
    // A grid and a request of the same time: the grid first, so the plan
    // sees the map of its moment.
    if (tg <= tr) {
      const GridNote note = *gn;
      grid_notes_.pop();
      if (t < processed_to_) ++stats_.late;
      apply_grid(note, t);
    } else {
      const Request r = *rq;
      requests_.pop();
      apply_request(r);
    }
    worked = true;
  }
  advance_poses(limit);
  if (limit > processed_to_) processed_to_ = limit;
  if (worked) health_.store(stats_);
  if (!worked && timeout_ns > 0) sleep_until(monotonic_now_ns() + std::min(timeout_ns, kNavigatorIdleNs));
}

navigator_detail::NavStats NavigatorDevice::stats() const noexcept {
  navigator_detail::NavStats v;
  health_.load(v);
  return v;
}

// --- publisher thread ----------------------------------------------------------

void NavigatorDevice::publish_due(TimeNs now, transport::MessageSink& sink) noexcept {
  const navigator_detail::PathForDisplay* p = display_.take_newest();
  if (p == nullptr) return;
  const transport::EncodedMessage msg = path_encoder_->encode(p->points.get(), p->count, p->goal_seq, p->cost, p->stamp);
  if (msg.ok()) sink.publish(config_.path_channel.c_str(), msg.data, msg.size, now);
}

}  // namespace rtfuse
