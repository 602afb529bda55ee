#!/usr/bin/env bash
# check_rejects.sh DEB --arch ARCH --version VERSION --source SRCDIR
#
# check_deb.sh must refuse a broken package, or passing it means nothing.
# Rebuilds DEB (a good package) with one defect at a time, with dpkg-deb,
# and expects check_deb.sh to exit 1 naming the defect:
#   a program missing, a config missing, a test program added, the wrong
#   Architecture, a conffile not registered, libstdc++6 dropped from
#   Depends while a program needs it (or kept while none does).
# Exit: 0 every defect caught, 1 one was not, 2 usage.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)

usage() {
  echo "usage: $0 DEB --arch ARCH --version VERSION --source SRCDIR" >&2
  exit 2
}
(($# == 7)) || usage
deb=$1
shift
args=("$@")
[[ -f $deb ]] || { echo "$0: $deb: no such file" >&2; exit 2; }
"$here/check_deb.sh" "$deb" "${args[@]}" >/dev/null || { echo "FAIL: check_deb.sh refuses the good package $deb" >&2; exit 1; }

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
name=$(basename "$deb")
failures=0

# variant LABEL EXPECTED-MESSAGE EDIT-COMMAND...: unpack, edit, repack under
# the good name (the name itself is checked too), run the check.
variant() {
  local label=$1 expect=$2
  shift 2
  local t=$tmp/$label
  mkdir -p "$t/out"
  dpkg-deb -R "$deb" "$t/pkg"
  (cd "$t/pkg" && "$@")
  dpkg-deb --root-owner-group -Zgzip -z1 -b "$t/pkg" "$t/out/$name" >/dev/null
  local rc=0 msg
  msg=$("$here/check_deb.sh" "$t/out/$name" "${args[@]}" 2>&1) || rc=$?
  if ((rc != 1)) || ! grep -qF -- "$expect" <<<"$msg"; then
    echo "FAIL: $label: check_deb.sh exit $rc, expected 1 and a message with '$expect':" >&2
    echo "$msg" >&2
    failures=$((failures + 1))
  else
    echo "ok: $label: $(grep -F -- "$expect" <<<"$msg" | head -n1)"
  fi
}

variant no-sim "missing /usr/bin/rtfuse-sim" rm usr/bin/rtfuse-sim
variant no-scenario "missing /etc/rtfuse/scenarios/straight.toml" \
  sh -c 'rm etc/rtfuse/scenarios/straight.toml && sed -i "\|/etc/rtfuse/scenarios/straight.toml|d" DEBIAN/conffiles'
variant no-jar "missing /usr/share/java/rtfuse_lcmtypes.jar" rm usr/share/java/rtfuse_lcmtypes.jar
variant test-binary "no test or bench programs" cp usr/bin/rtfused usr/bin/rtfuse_unit_core
variant wrong-arch "Architecture is 'i386'" sed -i 's/^Architecture: .*/Architecture: i386/' DEBIAN/control
variant conffile-unlisted "conffiles do not list exactly" sed -i '\|/etc/rtfuse/rtfused.toml|d' DEBIAN/conffiles
variant edited-config "/etc/rtfuse/rtfused.toml differs from config/robot_linux.toml" \
  sh -c 'echo "# not the source" >>etc/rtfuse/rtfused.toml'
if dpkg-deb -f "$deb" Depends | grep -q 'libstdc++6'; then
  variant no-libstdcxx-dep "lacks libstdc++6" \
    sed -i -E 's/libstdc\+\+6 \([^)]*\), //' DEBIAN/control
else
  variant extra-libstdcxx-dep "Depends has libstdc++6 but no program needs" \
    sed -i -E 's/^(Depends: )/\1libstdc++6 (>= 12), /' DEBIAN/control
fi

if ((failures)); then
  echo "check_rejects: $failures broken package(s) passed check_deb.sh" >&2
  exit 1
fi
echo "check_rejects: every broken package refused"
