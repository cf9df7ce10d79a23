# Completes a command line in an interactive zsh (on a pseudo-terminal, as a user's shell
# completes it) and prints each candidate the completion functions offer, one a line.
# Usage: zsh -f capture.zsh FUNCTION_DIR 'clothsim render -'
zmodload zsh/zpty || exit 3
zpty z zsh -f -i
setup=$(cat <<'SETUP'
PROMPT=''
fpath=("$CAPTURE_DIR" $fpath)
autoload -U compinit && compinit -u -D
# Each candidate offered is printed too; matching is left to zsh (-A collects the matches).
compadd() {
    if [[ ${@[1,(i)(-|--)]} == *-(O|A|D)\ * ]]; then
        builtin compadd "$@"
        return
    fi
    local -a __hits
    builtin compadd -A __hits "$@"
    local h
    for h in $__hits; do print -r -- "HIT $h"; done
    builtin compadd "$@"
}
comppostfuncs=(exit)
bindkey '^I' complete-word
print READY
SETUP
)
zpty -w z "CAPTURE_DIR=${(q)1}"
zpty -w z "$setup"
local line
while zpty -r z line; do [[ $line == READY* ]] && break; done
zpty -w -n z "$2"$'\t'
while zpty -r z line; do
    # The first candidate shares its line with the echo of what was typed.
    [[ $line == *HIT\ * ]] && print -r -- ${${line##*HIT }%$'\r'}
done
