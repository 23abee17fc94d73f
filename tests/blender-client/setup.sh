#!/usr/bin/env bash
# setup.sh VENV: installs what tests/blender.rs needs, once: a virtual environment VENV (under
# target/, kept between runs) with bpy 4.2.0 (Blender as a Python module, from the Python
# package registry; it needs CPython 3.11 exactly) and the numpy Blender 4.2 ships with.
# - CPython 3.11: `python3.11` on PATH (the machine's pyenv one, or Debian's /usr/bin/python3.11);
#   when there is none, Debian's python3.11 and python3.11-venv by apt-get (needs root).
# Exit 0 when everything is in place, 2 on a set-up problem (the log is named).
set -u
venv="${1:?usage: setup.sh VENV}"
log="${TMPDIR:-/tmp}/grainline-blender-setup.log"
ok() { [[ -x $venv/bin/python ]] && "$venv/bin/python" -c \
  'import sys, bpy; sys.exit(0 if bpy.app.version[:2] == (4, 2) else 1)' >/dev/null 2>&1; }
ok && exit 0
is311() { "$1" -c 'import sys, venv, ensurepip; sys.exit(0 if sys.version_info[:2] == (3, 11) else 1)' >/dev/null 2>&1; }
py=""
for c in python3.11 /usr/bin/python3.11 /usr/local/bin/python3.11; do
  if command -v "$c" >/dev/null 2>&1 && is311 "$c"; then py="$c"; break; fi
done
if [[ -z $py ]]; then
  echo "setup.sh: installing python3.11 and python3.11-venv ..." >&2
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends python3.11 python3.11-venv; } >"$log" 2>&1 \
    || { echo "setup.sh: could not install CPython 3.11; see $log" >&2; exit 2; }
  py=/usr/bin/python3.11
  is311 "$py" || { echo "setup.sh: $py is not a CPython 3.11 with venv" >&2; exit 2; }
fi
echo "setup.sh: bpy 4.2.0 into $venv ($py) ..." >&2
rm -rf "$venv"
{ "$py" -m venv "$venv" \
  && "$venv/bin/python" -m pip install --disable-pip-version-check -q "bpy==4.2.0" "numpy==1.26.4"; } >>"$log" 2>&1 \
  || { echo "setup.sh: could not install bpy 4.2.0; see $log" >&2; exit 2; }
ok || { echo "setup.sh: bpy 4.2 does not import from $venv; see $log" >&2; exit 2; }
exit 0
