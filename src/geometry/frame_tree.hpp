#pragma once
// A fixed-capacity tree of static frames, tf2-like. Built at configuration
// time (add() may fail with a message); lookups never allocate.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "core/fixed_string.hpp"
#include "geometry/rigid_transform.hpp"

namespace rtfuse::geometry {

class FrameTree {
 public:
  static constexpr int kMaxFrames = 48;
  using FrameName = FixedString<63>;

  // Adds the frame if unknown; returns its index, or -1 when full or the name
  // is empty or too long.
  int intern(std::string_view name);
  // Index of a known frame, -1 when unknown. Never allocates.
  int find(std::string_view name) const noexcept;
  std::string_view name(int index) const noexcept;
  int size() const noexcept { return count_; }

  // parent_T_child: pose of child in parent. Fails (returns false, *error set
  // unless error is null, tree unchanged) when the child already has a parent,
  // when the edge would make a cycle, when capacity is exceeded, on an empty,
  // over-long or self-parenting name, or on a non-finite / zero rotation.
  bool add(std::string_view parent, std::string_view child, const RigidTransform& parent_T_child,
           std::string* error);

  // target_T_source, or nothing when the two frames are not connected.
  std::optional<RigidTransform> lookup(int target, int source) const noexcept;
  std::optional<RigidTransform> lookup(std::string_view target, std::string_view source) const noexcept;

 private:
  // The tree is static, so every frame's pose in its root is computed once in
  // add(); a lookup is then one inverse and one product, whatever the depth.
  void update_roots() noexcept;
  bool fail(std::string_view parent, std::string_view child, std::string_view why,
            std::string* error) const;

  std::array<FrameName, kMaxFrames> names_{};
  std::array<std::int16_t, kMaxFrames> parent_{};  // -1: a root
  std::array<std::int16_t, kMaxFrames> root_{};
  std::array<RigidTransform, kMaxFrames> parent_T_frame_{};
  std::array<RigidTransform, kMaxFrames> root_T_frame_{};
  int count_ = 0;
};

}  // namespace rtfuse::geometry
