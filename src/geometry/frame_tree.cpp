#include "geometry/frame_tree.hpp"

#include <cmath>

namespace rtfuse::geometry {

namespace {

bool finite(const RigidTransform& t) noexcept {
  return t.translation.allFinite() && t.rotation.coeffs().allFinite();
}

// Names appear in error messages; an empty one would read as a missing word.
std::string shown(std::string_view name) {
  return name.empty() ? std::string("''") : std::string(name);
}

}  // namespace

int FrameTree::find(std::string_view name) const noexcept {
  for (int i = 0; i < count_; ++i) {
    if (names_[i] == name) return i;
  }
  return -1;
}

std::string_view FrameTree::name(int index) const noexcept {
  if (index < 0 || index >= count_) return {};
  return names_[index].view();
}

int FrameTree::intern(std::string_view name) {
  if (name.empty() || name.size() > FrameName::max_size()) return -1;
  const int known = find(name);
  if (known >= 0) return known;
  if (count_ >= kMaxFrames) return -1;
  const int i = count_++;
  names_[i].assign(name);
  parent_[i] = -1;
  root_[i] = static_cast<std::int16_t>(i);
  parent_T_frame_[i] = RigidTransform::identity();
  root_T_frame_[i] = RigidTransform::identity();
  return i;
}

bool FrameTree::fail(std::string_view parent, std::string_view child, std::string_view why,
                     std::string* error) const {
  if (error != nullptr) {
    *error = "static transform " + shown(parent) + " -> " + shown(child) + ": ";
    error->append(why);
  }
  return false;
}

bool FrameTree::add(std::string_view parent, std::string_view child, const RigidTransform& parent_T_child,
                    std::string* error) {
  // Every check runs before anything is changed: a failed add() leaves the tree as it was.
  const auto bad_name = [](std::string_view n, const char* role) -> std::string {
    if (n.empty()) return std::string(role) + " frame name is empty";
    if (n.size() > FrameName::max_size()) {
      return std::string(role) + " frame name '" + std::string(n) + "' is " + std::to_string(n.size()) +
             " characters long, the limit is " + std::to_string(FrameName::max_size());
    }
    return {};
  };
  for (const std::string& why : {bad_name(parent, "parent"), bad_name(child, "child")}) {
    if (!why.empty()) return fail(parent, child, why, error);
  }
  if (parent == child) {
    return fail(parent, child, "frame '" + std::string(child) + "' cannot be its own parent", error);
  }
  const int p = find(parent);
  const int c = find(child);
  if (c >= 0 && parent_[c] >= 0) {
    return fail(parent, child,
                "frame '" + std::string(child) + "' already has parent '" + std::string(name(parent_[c])) + "'",
                error);
  }
  // The child has no parent, so it is a root: the edge closes a cycle exactly
  // when the parent already hangs below it.
  if (p >= 0 && c >= 0 && root_[p] == c) {
    return fail(parent, child,
                "frame '" + std::string(parent) + "' already descends from '" + std::string(child) +
                    "', the edge would close a cycle",
                error);
  }
  if (!finite(parent_T_child)) {
    return fail(parent, child, "transform has a non-finite value", error);
  }
  if (parent_T_child.rotation.norm() < 1e-9) {
    return fail(parent, child, "rotation quaternion has zero norm", error);
  }
  const int needed = (p < 0 ? 1 : 0) + (c < 0 ? 1 : 0);
  if (count_ + needed > kMaxFrames) {
    return fail(parent, child,
                "frame tree is full (" + std::to_string(kMaxFrames) + " frames), cannot add " +
                    std::to_string(needed) + " more",
                error);
  }

  const int pi = intern(parent);
  const int ci = intern(child);
  parent_[ci] = static_cast<std::int16_t>(pi);
  // Normalised once here so that compositions in lookups stay rotations.
  parent_T_frame_[ci].rotation = parent_T_child.rotation.normalized();
  parent_T_frame_[ci].translation = parent_T_child.translation;
  update_roots();
  return true;
}

void FrameTree::update_roots() noexcept {
  // At most 48 frames, each at most 47 deep: cheap enough to redo in full
  // on every add(), which only happens at configuration time.
  for (int i = 0; i < count_; ++i) {
    RigidTransform root_T_i = parent_T_frame_[i];
    int top = i;
    for (int j = parent_[i]; j >= 0; j = parent_[j]) {
      root_T_i = parent_T_frame_[j] * root_T_i;
      top = j;
    }
    root_[i] = static_cast<std::int16_t>(top);
    root_T_frame_[i] = root_T_i;
  }
}

std::optional<RigidTransform> FrameTree::lookup(int target, int source) const noexcept {
  if (target < 0 || target >= count_ || source < 0 || source >= count_) return std::nullopt;
  if (root_[target] != root_[source]) return std::nullopt;
  if (target == source) return RigidTransform::identity();
  return root_T_frame_[target].inverse() * root_T_frame_[source];
}

std::optional<RigidTransform> FrameTree::lookup(std::string_view target,
                                                std::string_view source) const noexcept {
  return lookup(find(target), find(source));
}

}  // namespace rtfuse::geometry
