#!/usr/bin/env bash
# The bash completion the build makes (`mbstorm completion bash`), loaded into bash with
# Debian's bash-completion as a shell would, completes subcommands, every option of each
# subcommand and the values of options that take names (--model, --arrival, --addr-mode,
# --fc, ...), and leaves free values (--target) to the shell's default completion.
set -euo pipefail
mbstorm=$1
build=$(cd "$(dirname "$mbstorm")" && pwd)
script="$build/completion/mbstorm"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL $*" >&2; exit 1; }

framework=/usr/share/bash-completion/bash_completion
[ -f "$framework" ] || fail "no $framework (bash-completion; scripts/setup.sh installs it)"
[ -f "$script" ] || fail "no $script: build the mbstorm_completion target (part of the default build)"
"$mbstorm" completion bash >"$work/now"
cmp -s "$script" "$work/now" || fail "$script differs from what mbstorm completion bash prints now"

# complete LINE: what _mbstorm offers for the command line LINE (the cursor at its end),
# sorted, one per line; bash-completion loaded first, as in an interactive shell.
complete_line() {
  timeout 20 bash -c '
    source "$1" && source "$2" || exit 3
    read -ra COMP_WORDS <<<"$3"
    [[ $3 == *" " ]] && COMP_WORDS+=("")
    COMP_CWORD=$((${#COMP_WORDS[@]} - 1))
    COMP_LINE=$3
    COMP_POINT=${#3}
    # bash-completion re-splits COMP_LINE itself; "=" stays a word break as in a real shell.
    _mbstorm mbstorm "${COMP_WORDS[COMP_CWORD]}" "${COMP_WORDS[COMP_CWORD - 1]}"
    printf "%s\n" "${COMPREPLY[@]}"' bash "$framework" "$script" "$1" | sed '/^$/d' | sort
}
expect() {  # expect LINE WORD...: exactly these completions
  local got want
  got=$(complete_line "$1" | tr '\n' ' ')
  want=$(printf '%s\n' "${@:2}" | sed '/^$/d' | sort | tr '\n' ' ')
  [ "$got" = "$want" ] || fail "'$1<TAB>' offers '$got', expected '$want'"
}

"$mbstorm" --help >"$work/help"
mapfile -t subcommands < <(sed -n '/^Subcommands:/,$p' "$work/help" | sed -n 's/^  \([a-z][a-z-]*\) .*/\1/p')
expect "mbstorm " "${subcommands[@]}"
expect "mbstorm r" read replay run
expect "mbstorm --v" --version
expect "mbstorm run --mo" --model
expect "mbstorm run --model " closed open
expect "mbstorm run --model=" closed open
expect "mbstorm run -q --model o" open
expect "mbstorm run --arrival " even poisson
expect "mbstorm run --addr-mode " sequential uniform zipf
expect "mbstorm run --fc read_h" read_holding_registers
expect "mbstorm write --fc write_single_" write_single_coil write_single_register
expect "mbstorm serve --full-policy " evict refuse
expect "mbstorm serve --delay-kind " fixed uniform exponential
expect "mbstorm read --table h" holding_registers
expect "mbstorm read --type f" f32 f64
expect "mbstorm read --order " ABCD CDAB BADC DCBA
expect "mbstorm run --target "
expect "mbstorm run -c "

# Every option of every subcommand, as its --help names them.
checked=0
for sub in "${subcommands[@]}"; do
  mapfile -t options < <("$mbstorm" "$sub" --help | grep -E '^  -' | sed -E 's/^ +//; s/ .*//' |
    tr ',' '\n' | grep -E '^--[A-Za-z]')
  expect "mbstorm $sub --" "${options[@]}"
  checked=$((checked + ${#options[@]}))
done
echo "ok   subcommands, $checked long options of ${#subcommands[@]} subcommands, enumerated values"
