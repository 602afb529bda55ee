#!/usr/bin/env bash
# check_deb.sh DEB --arch ARCH --version VERSION --source SRCDIR
#
# Checks the rtfuse .deb without installing it: name, control fields,
# maintainer scripts, conffiles, and that it holds exactly what it must (the
# four programs for ARCH, every config of SRCDIR/config, the unit, the jar,
# the Python types and tools) and no other program (no test or bench binary).
# Prints every problem found, then exits 1 if there was one; 0 all good;
# 2 usage or an unreadable package.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=lib.sh
source "$here/lib.sh"

usage() {
  echo "usage: $0 DEB --arch ARCH --version VERSION --source SRCDIR" >&2
  exit 2
}
deb= arch= version= src=
while (($#)); do
  case "$1" in
    --arch) arch=${2:-}; shift 2 || usage ;;
    --version) version=${2:-}; shift 2 || usage ;;
    --source) src=${2:-}; shift 2 || usage ;;
    -*) echo "$0: unknown option '$1'" >&2; usage ;;
    *) [[ -z $deb ]] || usage; deb=$1; shift ;;
  esac
done
[[ -n $deb && -n $arch && -n $version && -n $src ]] || usage
[[ -f $deb ]] || { echo "$0: $deb: no such file" >&2; exit 2; }
[[ -d $src/config ]] || { echo "$0: $src is not the rtfuse source tree (no config/)" >&2; exit 2; }

problems=0
bad() { echo "FAIL: $(basename "$deb"): $*" >&2; problems=$((problems + 1)); }

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
dpkg-deb -e "$deb" "$tmp/control" 2>"$tmp/err" ||
  { echo "$0: $deb is not a readable .deb: $(cat "$tmp/err")" >&2; exit 2; }
dpkg-deb -x "$deb" "$tmp/data"
d=$tmp/data

# --- name and control ---------------------------------------------------------
[[ $(basename "$deb") == "rtfuse_${version}_${arch}.deb" ]] ||
  bad "file name is not rtfuse_${version}_${arch}.deb"
field() { dpkg-deb -f "$deb" "$1"; }
[[ $(field Package) == rtfuse ]] || bad "Package is '$(field Package)', not rtfuse"
[[ $(field Version) == "$version" ]] || bad "Version is '$(field Version)', not $version"
[[ $(field Architecture) == "$arch" ]] || bad "Architecture is '$(field Architecture)', not $arch"
depends=$(field Depends)
dep_names=$(tr ',' '\n' <<<"$depends" | sed -E 's/^ +//; s/[ (].*//' | sort -u)
for p in libc6 adduser; do
  grep -qx "$p" <<<"$dep_names" || bad "Depends ($depends) lacks $p"
done

for s in postinst prerm postrm; do
  if [[ ! -x $tmp/control/$s ]]; then
    bad "maintainer script $s missing or not executable"
  elif ! sh -n "$tmp/control/$s"; then
    bad "maintainer script $s is not valid sh"
  fi
done

# --- required files -------------------------------------------------------------
need() {  # need PATH [TYPE-TEST]
  local p=$1 t=${2:--f}
  test "$t" "$d/$p" || bad "missing /$p"
}
for prog in rtfused rtfuse-replay rtfuse-sim rtfuse-camera-snapshot rtfuse-canopen-node; do need "usr/bin/$prog" -x; done
expected_etc=()
for f in "$src"/config/*.toml; do expected_etc+=("etc/rtfuse/$(basename "$f")"); done
for f in "$src"/config/scenarios/*.toml; do expected_etc+=("etc/rtfuse/scenarios/$(basename "$f")"); done
for f in "$src"/config/calibration/*.conf; do expected_etc+=("etc/rtfuse/calibration/$(basename "$f")"); done
expected_etc+=(etc/rtfuse/rtfused.toml)
for p in "${expected_etc[@]}"; do need "$p"; done
need lib/systemd/system/rtfused.service
need usr/share/java/rtfuse_lcmtypes.jar
need usr/share/rtfuse/python/rtfuse/__init__.py
for f in "$src"/lcmtypes/*.lcm; do need "usr/share/rtfuse/python/rtfuse/$(basename "$f" .lcm).py"; done
for f in "$src"/tools/*.py; do need "usr/share/rtfuse/tools/$(basename "$f")" -x; done
for f in "$src"/tools/rtfuse_tools/*.py; do need "usr/share/rtfuse/tools/rtfuse_tools/$(basename "$f")"; done

# Shipped text is the source's own.
same() {  # same PACKAGED SOURCE
  [[ -f $d/$1 && -f $2 ]] || return 0  # reported above
  cmp -s "$d/$1" "$2" || bad "/$1 differs from ${2#"$src"/}"
}
for f in "$src"/config/*.toml; do same "etc/rtfuse/$(basename "$f")" "$f"; done
for f in "$src"/config/scenarios/*.toml; do same "etc/rtfuse/scenarios/$(basename "$f")" "$f"; done
for f in "$src"/config/calibration/*.conf; do same "etc/rtfuse/calibration/$(basename "$f")" "$f"; done
same etc/rtfuse/rtfused.toml "$src/config/robot_linux.toml"
same lib/systemd/system/rtfused.service "$src/packaging/rtfused.service"

# --- conffiles: exactly the files in /etc ------------------------------------
if [[ ! -f $tmp/control/conffiles ]]; then
  bad "no conffiles"
else
  diff <(sort "$tmp/control/conffiles") <(cd "$d" && find etc -type f | sed 's|^|/|' | sort) >"$tmp/conf.diff" ||
    bad "conffiles do not list exactly the files under /etc (< conffiles only, > data only):
$(grep '^[<>]' "$tmp/conf.diff")"
fi

# --- programs: the four, for ARCH, nothing else ---------------------------
case "$arch" in
  amd64) machine="Advanced Micro Devices X86-64" ;;
  arm64) machine="AArch64" ;;
  *) machine="" ;;
esac
mapfile -t elves < <(cd "$d" && find . -type f -print0 | xargs -0 -r file -N --mime-type |
  awk -F': ' '$2 ~ /application\/x-(pie-)?(executable|sharedlib|object)/ {print substr($1, 3)}' | sort)
expected_elves=$'usr/bin/rtfuse-camera-snapshot\nusr/bin/rtfuse-canopen-node\nusr/bin/rtfuse-replay\nusr/bin/rtfuse-sim\nusr/bin/rtfused'
[[ $(printf '%s\n' "${elves[@]}") == "$expected_elves" ]] ||
  bad "ELF files are [${elves[*]}], expected exactly usr/bin/rtfuse-camera-snapshot rtfuse-canopen-node rtfuse-replay rtfuse-sim rtfused (no test or bench programs)"
for e in "${elves[@]}"; do
  m=$(LC_ALL=C readelf -h "$d/$e" | awk -F': +' '/Machine:/ {print $2}')
  [[ -z $machine || $m == "$machine" ]] || bad "/$e is for '$m', not $arch ($machine)"
  LC_ALL=C readelf -S -W "$d/$e" | grep -q ' \.symtab ' && bad "/$e is not stripped"
  # libstdc++/libgcc_s in Depends exactly when a program needs them.
  needed=$(LC_ALL=C readelf -d -W "$d/$e" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
  for pair in libstdc++.so.6:libstdc++6 libgcc_s.so.1:libgcc-s1 liblcm.so.1:liblcm1 libgpiod.so.2:libgpiod2; do
    so=${pair%%:*} pkg=${pair#*:}
    if grep -qxF "$so" <<<"$needed" && ! grep -qxF "$pkg" <<<"$dep_names"; then
      bad "/$e needs $so but Depends ($depends) lacks $pkg"
    fi
  done
done
all_needed=$(for e in "${elves[@]}"; do LC_ALL=C readelf -d -W "$d/$e" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'; done | sort -u)
for pair in libstdc++.so.6:libstdc++6 libgcc_s.so.1:libgcc-s1; do
  so=${pair%%:*} pkg=${pair#*:}
  if grep -qxF "$pkg" <<<"$dep_names" && ! grep -qxF "$so" <<<"$all_needed"; then
    bad "Depends has $pkg but no program needs $so (static libstdc++/libgcc?)"
  fi
done

size=$(stat -c %s "$deb")
if ((problems)); then
  echo "check_deb: $problems problem(s) in $deb" >&2
  exit 1
fi
echo "check_deb: $(basename "$deb") OK: $arch, $((size / 1024)) KiB, $(cd "$d" && find . -type f | wc -l) files, Depends: $depends"
