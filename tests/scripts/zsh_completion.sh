#!/usr/bin/env bash
# The zsh completion the build makes (`mbstorm completion zsh`), loaded by compinit from fpath
# in an interactive zsh on a pseudo-terminal (zsh/zpty), as a user's shell loads it from
# vendor-completions: it completes subcommands, every option of each subcommand (every long
# option its --help lists) and the values of options that take names.
set -euo pipefail
mbstorm=$1
build=$(cd "$(dirname "$mbstorm")" && pwd)
script="$build/completion/_mbstorm"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL $*" >&2; exit 1; }

[ -f "$script" ] || fail "no $script: build the mbstorm_completion target (part of the default build)"
"$mbstorm" completion zsh >"$work/now"
cmp -s "$script" "$work/now" || fail "$script differs from what mbstorm completion zsh prints now"
zsh -n "$script" || fail "$script is not valid zsh"
mkdir "$work/fpath" "$work/bin"
cp "$script" "$work/fpath/_mbstorm"
ln -s "$mbstorm" "$work/bin/mbstorm"

# The completions zsh offers for a command line (the cursor at its end): every match the
# completion adds is printed between markers instead of being listed or inserted.
cat >"$work/capture.zsh" <<'ZSH'
zmodload zsh/zpty || exit 3
fpath_dir=$1 line=$2
zpty z zsh -f -i
zpty -w z "PROMPT='' RPROMPT=''; fpath=($fpath_dir \$fpath)"
zpty -w z 'autoload -U compinit && compinit -u -D'
zpty -w z "zstyle ':completion:*' list-grouped false; zstyle ':completion:*' menu no"
zpty -w z 'compadd() {
  if [[ " ${@[1,(i)(-|--)]} " == *" "-(O|A|D)" "* ]]; then builtin compadd "$@"; return; fi
  local -a hits; builtin compadd -A hits "$@"
  (( $#hits )) && print -rl -- "<m>"${^hits}
}'
# The end of the completion is told by a function compsys calls after it (nothing may be typed
# ahead of it: zle cuts a completion short when more input is pending).
zpty -w z '_capture_end() { print -- "<end>" }; comppostfuncs=(_capture_end)'
zpty -w z 'bindkey "^I" complete-word; print -- "<ready>"'
while zpty -r z got; do [[ $got == *'<ready>'* && $got != *print* ]] && break; done
zpty -w -n z "$line"$'\t'
while zpty -r z got; do
  [[ $got == *'<end>'* ]] && break
  [[ $got == *'<m>'* ]] && print -r -- "${${got##*<m>}%%$'\r'*}"
done
zpty -d z
ZSH

# offered LINE: the completions of LINE, sorted, one per line.
offered() {
  PATH="$work/bin:$PATH" timeout 20 zsh -f "$work/capture.zsh" "$work/fpath" "$1" | sed '/^$/d' | sort -u
}
expect() {  # expect LINE WORD...: exactly these completions
  local got want
  got=$(offered "$1" | tr '\n' ' ')
  want=$(printf '%s\n' "${@:2}" | sort -u | tr '\n' ' ')
  [ "$got" = "$want" ] || fail "'$1<TAB>' offers '$got', expected '$want'"
}

expect "mbstorm " run serve decode encode fuzz replay read write merge
expect "mbstorm run --mod" --model
expect "mbstorm run --model " closed open
expect "mbstorm read --type " u16 i16 u32 i32 u64 i64 f32 f64 string bits
expect "mbstorm fuzz --coverage-r" --coverage-report
expect "mbstorm write --fc re" read_coils read_discrete_inputs read_exception_status \
  read_fifo_queue read_file_record read_holding_registers read_input_registers \
  read_write_multiple_registers report_server_id

# Every long option each subcommand's --help lists is offered after "--".
for sub in run serve decode encode fuzz replay read write merge; do
  "$mbstorm" "$sub" --help | grep -oE '^ +(-[a-zA-Z0-9], ?)?--[a-z0-9-]+' | grep -oE -- '--[a-z0-9-]+' |
    sort -u >"$work/help-$sub"
  offered "mbstorm $sub --" >"$work/offered-$sub"
  missing=$(comm -23 "$work/help-$sub" "$work/offered-$sub")
  [ -z "$missing" ] || fail "mbstorm $sub --<TAB> does not offer: $(echo $missing)"
  [ "$(wc -l <"$work/help-$sub")" -gt 3 ] || fail "mbstorm $sub --help lists too few options to check"
done
echo "zsh completion: subcommands, every option and the named values complete"
