#!/usr/bin/env bash
# Install the peer contact codes that benchmarks/peers/ measures us against.
# Benchmarks only: nothing in contactqvi, its tests or `make test` needs them.
#
#   scripts/install-peers.sh            both peers
#   scripts/install-peers.sh getfem     GetFEM 5.4 only
#   scripts/install-peers.sh kratos     Kratos 10.4.4 only
#
#  * GetFEM: Debian trixie's python3-getfem (5.4.4, for /usr/bin/python3 = 3.13; the
#    bookworm build needs Python < 3.12), through scripts/install-deps.sh, which pins
#    trixie at priority 100 on an older Debian and installs with -t trixie. Our venv
#    (.venv, --system-site-packages) sees it.
#  * Kratos Multiphysics 10.4.4 from PyPI into its own venv, build/kratos-venv (made
#    with /usr/bin/python3 -m venv --system-site-packages, so that Debian's numpy and
#    gmsh are visible; pip resolves only the Kratos wheels and what they need).
#
# Idempotent: a peer that is already installed (at the pinned version) is left alone.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
KRATOS_VERSION=${KRATOS_VERSION:-10.4.4}
KRATOS_VENV=${KRATOS_VENV:-$root/build/kratos-venv}
peers=("$@")
[ ${#peers[@]} -gt 0 ] || peers=(getfem kratos)

install_getfem() {
    if /usr/bin/python3 -c 'import getfem' 2>/dev/null; then
        echo "install-peers: GetFEM $(dpkg-query -W -f='${Version}' python3-getfem) already installed"
        return
    fi
    bash "$here/install-deps.sh" <(echo python3-getfem)
    /usr/bin/python3 -c 'import getfem'
    echo "install-peers: GetFEM $(dpkg-query -W -f='${Version}' python3-getfem)"
}

install_kratos() {
    local py="$KRATOS_VENV/bin/python"
    # Importing Kratos prints a banner (and a line at exit): ask pip's metadata for the version.
    local version="import importlib.metadata as m; print(m.version('KratosContactStructuralMechanicsApplication'))"
    # The constitutive laws application holds HyperElastic3DLaw (the ironing case's neo-Hookean bodies).
    local modules="import KratosMultiphysics.ContactStructuralMechanicsApplication, KratosMultiphysics.ConstitutiveLawsApplication"
    if [ -x "$py" ] && [ "$("$py" -c "$version" 2>/dev/null)" = "$KRATOS_VERSION" ] \
        && "$py" -c "$modules" >/dev/null 2>&1; then
        echo "install-peers: Kratos $KRATOS_VERSION already installed in $KRATOS_VENV"
        return
    fi
    # venv needs python3-venv (and the pip/setuptools wheels from trixie for ensurepip).
    bash "$here/install-deps.sh" <(printf '%s\n' python3-venv python3-pip-whl python3-setuptools-whl)
    /usr/bin/python3 -m venv --system-site-packages "$KRATOS_VENV"
    "$py" -m pip install --quiet --disable-pip-version-check \
        "kratosmultiphysics==$KRATOS_VERSION" \
        "kratosstructuralmechanicsapplication==$KRATOS_VERSION" \
        "kratoscontactstructuralmechanicsapplication==$KRATOS_VERSION" \
        "kratosconstitutivelawsapplication==$KRATOS_VERSION" 2> >(grep -v "is ignored: it is neither" >&2)
    "$py" -c "$modules" >/dev/null
    echo "install-peers: Kratos $("$py" -c "$version") in $KRATOS_VENV"
}

for peer in "${peers[@]}"; do
    case "$peer" in
        getfem) install_getfem ;;
        kratos) install_kratos ;;
        *) echo "install-peers: unknown peer '$peer' (getfem, kratos)" >&2; exit 2 ;;
    esac
done
