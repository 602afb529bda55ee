#pragma once
// The navigator: goals in, paths planned on the mapper's grid, and, with
// [navigation] follow on, velocity commands out. A worker device
// (device_descriptor.hpp, DeviceScheduling::kWorker) whose host is the
// mapper, in three parts that never wait for each other:
//
//   LCM thread     on_input(): goals and stops decoded and checked, into
//                  SPSC rings (full: dropped, counted).
//   mapper thread  on_grid() / on_map_current(): each new grid copied into
//                  a free grid slot (none free: dropped, counted), and the
//                  stamp of every keyframe taken in.
//   loop thread    fill_snapshot(): the tick's estimate to the planner;
//                  goals and stops taken; the planner's results adopted
//                  once due; every command period the path follower and
//                  the command gate (navigation/) give the command and its
//                  stop reason into the snapshot, which the publisher sends
//                  as cmd_vel and nav_status.
//   navigator      step(): grids, goals and re-plan requests in the order
//   thread         of their times (a grid's: its stamp + map_delay; a
//                  request's: its tick), each once the loop has passed it:
//                  the costmap updated, the path checked against it and
//                  re-planned when blocked, goals planned; each result
//                  tagged with its time, for the loop to adopt at that time
//                  + plan_delay.
//
// So what the robot does follows from the ticks, the grids and the inputs
// alone, never from when the navigator's thread ran: a replay or a
// lockstep drive (step(0) after every tick, after the mapper's) commands
// the same, bit for bit, as the live run did, unless a grid or a result
// was late live (counted: `late`).
//
// Allocates in create() only.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "core/seq_cell.hpp"
#include "core/spsc_ring.hpp"
#include "core/triple_buffer.hpp"
#include "navigation/command_gate.hpp"
#include "navigation/costmap.hpp"
#include "navigation/grid_planner.hpp"
#include "navigation/path_follower.hpp"
#include "navigation/plan_status.hpp"
#include "runtime/devices/device.hpp"
#include "runtime/devices/grid_consumer.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "transport/nav_messages.hpp"

namespace rtfuse {

extern const char* const kNavigatorKeys[19];

namespace navigator_detail {
// Ring slots (outside the class, as the mapper's: default-constructible
// types for SpscRing before the class ends).
struct LoopPose {
  TimeNs tick = 0;
  bool ok = false;  // initialised and finite
  double x = 0.0, y = 0.0, yaw = 0.0;
};
enum class RequestKind : std::uint8_t { kGoal, kOffPath, kDone };
struct Request {
  TimeNs tick = 0;
  RequestKind kind = RequestKind::kGoal;
  std::int32_t goal_seq = 0;
  double goal_x = 0.0, goal_y = 0.0;
  LoopPose start;
};
struct GridNote {
  TimeNs stamp = 0;
  int slot = -1;  // -1: a keyframe taken in, no new grid
};
// Why a plan was made.
enum class PlanCause : std::uint8_t { kNone, kGoal, kOffPath, kBlocked, kMapChanged };
struct Result {
  TimeNs time = 0;      // the grid's or the request's
  TimeNs apply_at = 0;  // time + plan_delay
  TimeNs map_stamp = 0; // newest keyframe taken in, as of time (0: none)
  std::int32_t goal_seq = 0;
  PlanCause cause = PlanCause::kNone;  // kNone: no plan in this result
  navigation::PlanStatus status = navigation::PlanStatus::kOk;
  bool blocked = false;  // the path followed is blocked and no other was found
  int slot = -1;         // the path's points (status kOk)
  int points = 0;
  double cost = 0.0;
};
struct NavStats {
  std::int64_t plans = 0;
  std::int64_t plan_failures = 0;
  std::int64_t replans_blocked = 0;
  std::int64_t replans_map = 0;
  std::int64_t expansions = 0;  // of the last plan
  TimeNs plan_ns = 0;           // the last plan's
  TimeNs max_plan_ns = 0;
  std::int64_t grids = 0;
  TimeNs costmap_ns = 0;        // the last update's
  std::int64_t speckles = 0;    // lone obstacle cells dropped from the last grid
  std::int64_t late = 0;        // grids processed after their time had passed (live only)
};
struct GoalInput {
  transport::NavGoal goal;
  bool frame_ok = false;
  int error = 0;  // transport::DecodeResult when not kOk
};
struct StopInput {
  bool stop = false;
};
struct PathForDisplay {
  std::unique_ptr<transport::PathPoint2[]> points;
  int count = 0;
  std::int32_t goal_seq = 0;
  double cost = 0.0;
  TimeNs stamp = 0;
};
}  // namespace navigator_detail

class NavigatorDevice final : public Device, public GridConsumer {
 public:
  static constexpr int kGridSlots = 4;
  static constexpr int kPathSlots = 8;

  // On the grids of `mapper`; the configuration is the core's
  // ([navigation], [mapping]). Null with *error when it cannot work.
  static std::unique_ptr<NavigatorDevice> create(GridSource& mapper, FusionCore& core, int slot, std::string* error);
  ~NavigatorDevice() override;

  // Device.
  void step(TimeNs timeout_ns) noexcept override;
  void fill_snapshot(Snapshot& s) noexcept override;
  void publish_due(TimeNs now, transport::MessageSink& sink) noexcept override;
  void on_input(int channel, const std::uint8_t* data, int size, TimeNs now) noexcept override;
  std::int64_t inputs_taken(int channel) const noexcept override {
    return channel == kGoalInput ? goals_taken_ : channel == kStopInput ? stops_taken_ : 0;
  }
  GridConsumer* grid_consumer() noexcept override { return this; }

  // GridConsumer.
  void on_grid(const std::int8_t* cells, TimeNs stamp) noexcept override;
  void on_map_current(TimeNs stamp) noexcept override;

  // The input channels, in on_input's order.
  enum Input : int { kGoalInput = 0, kStopInput = 1 };

  // For tests and tools, between lockstep steps.
  const navigation::Costmap& costmap() const noexcept { return *costmap_; }
  const GridLayout& layout() const noexcept { return layout_; }
  const navigation::PathFollower& follower() const noexcept { return *follower_; }
  navigator_detail::NavStats stats() const noexcept;

 private:
  using LoopPose = navigator_detail::LoopPose;
  using Request = navigator_detail::Request;
  using GridNote = navigator_detail::GridNote;
  using Result = navigator_detail::Result;
  using PlanCause = navigator_detail::PlanCause;

  using GoalInput = navigator_detail::GoalInput;
  using StopInput = navigator_detail::StopInput;

  explicit NavigatorDevice(int slot);

  // Loop thread.
  void take_inputs(const Snapshot& s, TimeNs now) noexcept;
  void adopt_results(TimeNs now) noexcept;
  void command(Snapshot& s, TimeNs now) noexcept;
  void request(const Request& r) noexcept;
  void reject_goal(const char* why) noexcept;

  // Navigator thread.
  void advance_poses(TimeNs t) noexcept;
  void apply_grid(const GridNote& note, TimeNs t) noexcept;
  void apply_request(const Request& r) noexcept;
  // Plans from `from` to the current goal; the result, tagged with t,
  // to the loop.
  void plan_and_send(TimeNs t, const LoopPose& from, PlanCause cause) noexcept;
  bool remaining_path_blocked() const noexcept;
  void send(Result r) noexcept;

  int slot_ = -1;
  NavigationSection config_;
  std::string world_frame_;
  GridLayout layout_;
  TimeNs map_delay_ns_ = 0;
  TimeNs plan_delay_ns_ = 0;
  TimeNs command_period_ns_ = 0;
  int max_points_ = 0;

  // LCM thread -> loop.
  transport::NavInputDecoder decoder_;
  SpscRing<GoalInput> goals_{8};
  SpscRing<StopInput> stops_{8};
  std::atomic<std::int64_t> inputs_dropped_{0};
  std::atomic<std::int64_t> inputs_bad_{0};

  // Mapper thread -> navigator thread.
  std::unique_ptr<std::int8_t[]> grid_slots_[kGridSlots];
  SpscRing<int> free_grids_{kGridSlots + 1};  // the navigator returns, the mapper takes
  int spare_grid_ = -1;  // mapper thread: a slot whose note the ring refused, kept for the next
  SpscRing<GridNote> grid_notes_{256};
  std::atomic<std::int64_t> grids_dropped_{0};

  // Loop -> navigator thread.
  SpscRing<LoopPose> poses_;
  SpscRing<Request> requests_{64};
  std::atomic<TimeNs> loop_tick_{0};
  std::atomic<std::int64_t> lost_{0};  // poses or requests the rings had no room for
  static_assert(std::atomic<TimeNs>::is_always_lock_free);

  // Navigator thread -> loop.
  std::unique_ptr<navigation::Point2[]> path_slots_[kPathSlots];
  SpscRing<int> free_paths_{kPathSlots + 1};  // the loop returns, the navigator takes
  int spare_path_ = -1;  // navigator thread: a slot whose result the ring refused, kept for the next
  SpscRing<Result> results_{256};

  // Navigator thread.
  std::unique_ptr<navigation::Costmap> costmap_;
  std::unique_ptr<std::int8_t[]> filtered_;  // the grid without its speckles (drop_speckles)
  std::unique_ptr<navigation::GridPlanner> planner_;
  navigation::PlannerParams planner_params_;
  LoopPose pose_;  // the loop's newest estimate up to the event in work
  TimeNs processed_to_ = 0;  // every event up to this tick is done
  TimeNs map_stamp_ = 0;
  bool goal_active_ = false;
  std::int32_t goal_seq_ = 0;
  double goal_x_ = 0.0, goal_y_ = 0.0;
  bool path_ok_ = false;  // a path to the current goal was sent
  std::unique_ptr<navigation::Point2[]> path_;  // the last path sent, for the blocked check
  std::unique_ptr<navigation::GridCell[]> smoothed_;  // workspace of the smoothing
  int path_size_ = 0;
  navigator_detail::NavStats stats_;
  SeqLatch<navigator_detail::NavStats> health_;
  TripleBuffer<navigator_detail::PathForDisplay> display_;

  // Loop thread.
  std::unique_ptr<navigation::PathFollower> follower_;
  std::unique_ptr<navigation::CommandGate> gate_;
  NavSnapshot nav_;
  TimeNs next_command_ = 0;
  bool any_command_ = false;
  bool goal_active_loop_ = false;
  bool stop_latched_ = false;
  bool have_path_ = false;
  bool blocked_ = false;
  TimeNs loop_map_stamp_ = 0;
  TimeNs off_path_asked_ = -1;  // tick of the outstanding off-path request
  std::int64_t goals_taken_ = 0;
  std::int64_t stops_taken_ = 0;
  std::int64_t goals_rejected_ = 0;
  std::int64_t reached_ = 0;
  std::int64_t commands_ = 0;
  std::int64_t replans_off_path_ = 0;

  // Publisher thread.
  std::unique_ptr<transport::PathEncoder> path_encoder_;
};

}  // namespace rtfuse
