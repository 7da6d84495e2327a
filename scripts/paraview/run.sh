#!/usr/bin/env bash
# Render the standard ParaView views of a result directory (`make paraview`).
#
#   scripts/paraview/run.sh RESULT_DIR [IMAGE_DIR [--step N | --time]]
#
# A dynamic result (a case with [dynamics]) gets its views over time (pv_time.py):
# IMAGE_DIR/paraview_time_NN.png and RESULT_DIR/paraview_time.pvsm for the GUI.
# Installs ParaView 5.13 from Debian (scripts/paraview/packages.txt, through
# scripts/install-deps.sh) when missing. Its Python modules (python3-paraview)
# conflict with python3-vtk9, which pyvista needs, so they are not installed but
# unpacked with dpkg -x into build/paraview and put first on PYTHONPATH for
# ParaView's pvbatch (the unpacked pvpython would put the system's VTK modules
# first). Renders headless under xvfb-run.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/../.." && pwd)
[ $# -ge 1 ] || { echo "usage: $0 RESULT_DIR [IMAGE_DIR [--step N | --time]]" >&2; exit 2; }
result_dir=$1
image_dir=${2:-$1}
shift $(( $# >= 2 ? 2 : 1 ))  # the rest goes to pv_views.py (--step N, --time)

bash "$repo/scripts/install-deps.sh" "$here/packages.txt"

version=$(dpkg-query -W -f='${Version}' paraview)
unpacked=$repo/build/paraview/$version
if [ ! -d "$unpacked/usr/lib/python3/dist-packages/paraview" ]; then
    echo "paraview: unpacking python3-paraview $version into $unpacked"
    download=$(mktemp -d)
    chmod 777 "$download"  # apt-get download runs as _apt
    (cd "$download" && apt-get download -q "python3-paraview=$version" >/dev/null)
    rm -rf "$unpacked"
    mkdir -p "$unpacked"
    dpkg -x "$download"/python3-paraview_*.deb "$unpacked"
    rm -rf "$download"
fi

export PYTHONPATH=$unpacked/usr/lib/python3/dist-packages${PYTHONPATH:+:$PYTHONPATH}
# pvbatch is an MPI program: let it start as root on a single rank.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,sm
echo "paraview: $(pvbatch --version 2>/dev/null | head -1), rendering $result_dir to $image_dir"
# A display number away from :99 (pyvista's start_xvfb), where concurrent X servers
# race; one retry when X itself failed (exit 2 is the script's own "file/field missing").
for attempt in 1 2; do
    rc=0
    xvfb-run -a -n $((200 + $$ % 500)) -s "-screen 0 1920x1200x24" \
        pvbatch "$here/pv_views.py" "$result_dir" --out "$image_dir" "$@" || rc=$?
    [ $rc -eq 0 ] || [ $rc -eq 2 ] && exit $rc
    echo "paraview: pvbatch exited with $rc (attempt $attempt)" >&2
done
exit $rc
