# Shared by the shell tests of tests/scripts: a scratch folder removed on exit, check() counting
# failures, contains(). Source it after setting `name`; call finish_checks at the end.
work=$(mktemp -d "${TMPDIR:-/tmp}/${name:-prt_test}.XXXXXX")
trap 'rm -rf "$work"' EXIT
failures=0
check() {  # check DESCRIPTION COMMAND...: the command must succeed
    local what=$1
    shift
    if "$@"; then
        echo "ok: $what"
    else
        echo "FAILED: $what"
        failures=$((failures + 1))
    fi
}
contains() { grep -qF -- "$2" "$1"; }
# contains_any FILE TEXT...: FILE contains one of the texts.
contains_any() {
    local file=$1 text
    shift
    for text in "$@"; do grep -qF -- "$text" "$file" && return 0; done
    return 1
}
# The exit status of the test: 0 when every check passed.
finish_checks() {
    echo "$failures failed checks"
    [ "$failures" = 0 ]
}
