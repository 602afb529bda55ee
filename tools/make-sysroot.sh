#!/usr/bin/env bash
# make-sysroot.sh DIR [--arch arm64]
#
# Builds a stand-in target sysroot in DIR from Debian 12 packages of the
# target architecture: each package is fetched with `apt-get download` and
# unpacked with `dpkg -x`. Nothing is installed on the host and the host's
# dpkg architecture list is left alone: apt runs with its own state folder
# (DIR/.apt) that knows only the target architecture. That matters for LCM:
# installing liblcm-dev:arm64 would remove liblcm-dev:amd64 and replace the
# host's lcm-gen with an arm64 binary.
#
# A real TX2 build points CMAKE_SYSROOT at NVIDIA's Linux_for_Tegra/rootfs
# instead (see README, "Deploy to a Jetson"); this sysroot is what CI builds
# and emulates against. Re-running with the same package list is a no-op.
set -euo pipefail

usage() { echo "usage: make-sysroot.sh DIR [--arch arm64]" >&2; exit 2; }
[[ $# -ge 1 ]] || usage
dir=$1; shift
arch=arm64
while [[ $# -gt 0 ]]; do
  case "$1" in
    --arch) arch=${2:?}; shift 2 ;;
    *) usage ;;
  esac
done

# What rtfuse builds, links and runs its tests against on the target. Only
# runtime and -dev packages of the libraries themselves: compilers and host
# tools (lcm-gen, javac, python) come from the host.
packages=(
  libc6 libc6-dev linux-libc-dev libcrypt1 libcrypt-dev
  libgcc-s1 libstdc++6 libatomic1
  liblcm1 liblcm-dev libglib2.0-0 libpcre2-8-0 libffi8 libmount1 libblkid1 libselinux1 zlib1g
  libgpiod2 libgpiod-dev
  libeigen3-dev libtomlplusplus3 libtomlplusplus-dev libcli11-dev
  libgtest-dev libgmock-dev googletest libbenchmark1debian libbenchmark-dev
  # the stereo PNG writer of the snapshot tool (src/apps/stereo_png.cpp)
  libpng16-16 libpng-dev
  # XXH64, inlined: the header only (src/core/xxh64.hpp)
  libxxhash-dev
  # PCG32, header-only (src/vision/stereo_egomotion.cpp)
  libpcg-cpp-dev
  # map_server YAML files (src/apps/map_server_map.cpp, rtfuse-plan)
  libyaml-cpp0.7 libyaml-cpp-dev
)

mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
stamp="$dir/.rtfuse-sysroot"
want="$arch ${packages[*]}"
if [[ -f "$stamp" && "$(cat "$stamp")" == "$want" ]]; then
  echo "make-sysroot: $dir is up to date ($arch, ${#packages[@]} packages)"
  exit 0
fi

apt_dir="$dir/.apt"
mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial" "$apt_dir/debs"
: >"$apt_dir/status"
apt_opts=(
  -o "APT::Architecture=$arch"
  -o "APT::Architectures::=$arch"
  -o "Dir::State=$apt_dir"
  -o "Dir::State::Lists=$apt_dir/lists"
  -o "Dir::State::status=$apt_dir/status"
  -o "Dir::Cache=$apt_dir/cache"
  -o "Debug::NoLocking=1"
  -o "APT::Sandbox::User=root"
)

echo "make-sysroot: fetching the $arch package index"
apt-get "${apt_opts[@]}" -qq update

echo "make-sysroot: downloading ${#packages[@]} $arch packages"
(cd "$apt_dir/debs" && apt-get "${apt_opts[@]}" -qq download "${packages[@]}")

for deb in "$apt_dir"/debs/*.deb; do
  dpkg -x "$deb" "$dir"
done

# Debian's -dev symlinks and linker scripts that use absolute paths are
# resolved by the cross linker inside --sysroot; symlinks are not, so make
# every absolute symlink relative to the sysroot.
while IFS= read -r -d '' link; do
  target=$(readlink "$link")
  [[ "$target" == /* ]] || continue
  rel=$(realpath -m --relative-to="$(dirname "$link")" "$dir$target")
  ln -sfn "$rel" "$link"
done < <(find "$dir" -path "$apt_dir" -prune -o -type l -print0)

printf '%s' "$want" >"$stamp"
echo "make-sysroot: $dir ready ($(du -sh --exclude=.apt "$dir" | cut -f1), $arch)"
