# shellcheck shell=bash
# The one way glint's scripts make a Python virtual environment (issue 40 item 7): a
# library, sourced, not run.
#
#   source "$root/scripts/lib/venv.sh"
#   glint_venv [--python X.Y] DIR PIN...    # DIR holds what `pip install PIN...` installs
#   glint_venv [--python X.Y] DIR -r FILE   # DIR holds what `pip install -r FILE` installs
#   glint_venv_current DIR PIN... | DIR -r FILE   # true when DIR holds exactly those now
#
# DIR is reused while it was made with the same pins (or the same text of FILE): they
# are written to DIR/.glint-pins once pip has installed them, so a changed pin list or
# requirements file, or an interrupted install, makes the venv afresh.
#
# The interpreter: $PYTHON, else the first of python3, python3.14, python3.13,
# python3.12 and pyenv's installed versions that is X.Y or newer (--python; without it,
# any version, so python3 when it exists). pip's output goes to stderr: a benchmark's
# stdout stays its own. DIR is replaced only when it is a venv (it holds pyvenv.cfg) or
# empty: an override such as GLINT_VENV pointing at another folder by mistake is
# refused, not deleted. Messages start with the calling script's name.

# Prints the first usable interpreter (at least version $1, X.Y, when given).
glint_python() {
    local min=${1:-} p candidates=()
    local check='import sys'
    if [[ -n "$min" ]]; then
        local major=${min%%.*} minor=0
        [[ "$min" == *.* ]] && minor=${min#*.}
        check="import sys; sys.exit(sys.version_info < ($major, $minor))"
    fi
    candidates=(${PYTHON:+"$PYTHON"} python3 python3.14 python3.13 python3.12)
    if command -v pyenv >/dev/null 2>&1; then
        candidates+=("$(pyenv root)"/versions/3.*/bin/python3)
    fi
    for p in "${candidates[@]}"; do
        if command -v "$p" >/dev/null 2>&1 && "$p" -c "$check" 2>/dev/null; then
            echo "$p"
            return 0
        fi
    done
    return 1
}

# Sets _glint_key (what .glint-pins records) and _glint_install (pip's arguments) from
# `PIN...` or `-r FILE`.
_glint_venv_spec() {
    local IFS=' '
    if [[ "${1:-}" == -r ]]; then
        if [[ ! -f "${2:-}" ]]; then
            echo "${0##*/}: no requirements file '${2:-}'" >&2
            return 1
        fi
        _glint_key=$(cat "$2")
        _glint_install=(-r "$2")
    elif [[ $# -gt 0 ]]; then
        _glint_key="$*"
        _glint_install=("$@")
    else
        echo "${0##*/}: glint_venv needs pins or -r FILE" >&2
        return 1
    fi
}

# True when venv $1 was made with what _glint_key records.
_glint_venv_holds() {
    [[ -x "$1/bin/python" && "$(cat "$1/.glint-pins" 2>/dev/null)" == "$_glint_key" ]]
}

glint_venv_current() {
    local dir=${1:?glint_venv_current DIR PIN...}
    shift
    _glint_venv_spec "$@" && _glint_venv_holds "$dir"
}

glint_venv() {
    local min= me=${0##*/} python
    if [[ "${1:-}" == --python ]]; then
        min=${2:?glint_venv --python X.Y}
        shift 2
    fi
    local dir=${1:?glint_venv DIR PIN...}
    shift
    _glint_venv_spec "$@" || return 1
    if _glint_venv_holds "$dir"; then
        return 0
    fi
    if ! python=$(glint_python "$min"); then
        echo "$me: needs Python >= ${min:-3} (set PYTHON)" >&2
        return 1
    fi
    if [[ -e "$dir" && ! -f "$dir/pyvenv.cfg" ]] && [[ ! -d "$dir" || -n "$(ls -A "$dir")" ]]; then
        echo "$me: $dir is not a venv; not replacing it (remove it, or choose another)" >&2
        return 1
    fi
    echo "$me: creating $dir with $python" >&2
    rm -rf "$dir"
    "$python" -m venv "$dir" || return 1
    "$dir/bin/python" -m pip install --quiet --disable-pip-version-check \
        "${_glint_install[@]}" >&2 || return 1
    printf '%s\n' "$_glint_key" >"$dir/.glint-pins"
}
