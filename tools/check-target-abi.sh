#!/usr/bin/env bash
# check-target-abi.sh BINARY... --glibc X.Y [--glibcxx 3.4.N] [--gcc N.N]
#
# Lists every versioned dynamic symbol the binaries need that is newer than
# the target board provides, and exits 1 if there is one: a binary asking
# for GLIBC_2.34 fails on a JetPack 4.6 TX2 (glibc 2.27) at start with a
# loader error, long after it built. Exit 0: nothing newer; 2: usage, a
# missing file or not an ELF file.
#
# readelf reads ELF of any architecture, so this checks aarch64 binaries on
# an x86 host. Versions of glibc (GLIBC_), and with their options libstdc++
# (GLIBCXX_) and libgcc_s (GCC_), are judged; a statically linked libstdc++
# and libgcc leave no such references at all.
set -euo pipefail

usage() {
  echo "usage: $0 BINARY... --glibc X.Y [--glibcxx 3.4.N] [--gcc N.N]" >&2
  echo "  e.g. $0 build/aarch64/src/apps/rtfused --glibc 2.27   (JetPack 4.6 / L4T R32.7)" >&2
  exit 2
}

binaries=() glibc= glibcxx= gcc=
while (($#)); do
  case "$1" in
    --glibc) glibc=${2:-}; shift 2 || usage ;;
    --glibcxx) glibcxx=${2:-}; shift 2 || usage ;;
    --gcc) gcc=${2:-}; shift 2 || usage ;;
    -h | --help) usage ;;
    -*) echo "$0: unknown option '$1'" >&2; usage ;;
    *) binaries+=("$1"); shift ;;
  esac
done
((${#binaries[@]})) && [[ -n $glibc ]] || usage
for v in "$glibc" "$glibcxx" "$gcc"; do
  [[ -z $v || $v =~ ^[0-9]+(\.[0-9]+)*$ ]] || { echo "$0: '$v' is not a version like 2.27" >&2; exit 2; }
done
command -v readelf >/dev/null || { echo "$0: readelf not found (apt-get install binutils)" >&2; exit 2; }

# newer A B: true when version A > version B.
newer() { [[ $1 != "$2" && $(printf '%s\n%s\n' "$1" "$2" | sort -V | tail -n1) == "$1" ]]; }

status=0
for bin in "${binaries[@]}"; do
  if [[ ! -f $bin ]]; then
    echo "$0: $bin: no such file" >&2; exit 2
  fi
  if ! header=$(LC_ALL=C readelf -h "$bin" 2>&1); then
    echo "$0: $bin: not an ELF file (${header##*: })" >&2; exit 2
  fi
  machine=$(awk -F: '/Machine:/ {gsub(/^ +/, "", $2); print $2}' <<<"$header")
  # "memcpy@GLIBC_2.17 (2)" in the dynamic symbol table; undefined ones are
  # what the binary needs from the target's libraries.
  mapfile -t needs < <(LC_ALL=C readelf --dyn-syms -W "$bin" |
    awk '$7 == "UND" && $8 ~ /@/ {split($8, a, "@"); print a[2] " " a[1]}' | sort -u)
  too_new=()
  for line in "${needs[@]}"; do
    ver=${line%% *} sym=${line#* }
    case "$ver" in
      GLIBC_[0-9]*) limit=$glibc v=${ver#GLIBC_} ;;
      GLIBCXX_[0-9]*) limit=$glibcxx v=${ver#GLIBCXX_} ;;
      GCC_[0-9]*) limit=$gcc v=${ver#GCC_} ;;
      *) continue ;;  # CXXABI_ and others: not judged
    esac
    [[ -n $limit ]] || continue  # no limit given for that library
    if newer "$v" "$limit"; then too_new+=("$ver $sym"); fi
  done
  if ((${#too_new[@]} == 0)); then
    echo "$bin ($machine): OK, no symbol newer than glibc $glibc${glibcxx:+, libstdc++ $glibcxx}${gcc:+, libgcc $gcc}"
    continue
  fi
  status=1
  echo "$bin ($machine): ${#too_new[@]} symbols newer than the target (glibc $glibc${glibcxx:+, libstdc++ $glibcxx}${gcc:+, libgcc $gcc}):"
  printf '%s\n' "${too_new[@]}" | sort -V | awk '
    { if ($1 != v) { if (v != "") print "  " v ": " s; v = $1; s = $2 } else s = s ", " $2 }
    END { print "  " v ": " s }'
done
if ((status)); then
  echo "The target's loader refuses these: build against its own sysroot (Linux_for_Tegra/rootfs), see README." >&2
fi
exit $status
