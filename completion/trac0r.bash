# bash completion for trac0r                                     -*- shell-script -*-
#
# Installed as share/bash-completion/completions/trac0r. The commands, benchmarks,
# options and option values are read from the `--help` texts of the trac0r being
# completed (the one on the command line), so they follow the binary; only the kind of
# argument an option takes (a file, a directory, a scene, a name) is decided here, from
# its metavariable in the help (FILE, PREFIX, DIR, SCENE, NAME, DEV, LIST).

# The help text of "$@" (trac0r's path first), or nothing.
_trac0r_help() {
    "$@" --help 2>/dev/null
}

# Words listed in a help section: the first word of each line indented by two spaces
# between the line "$2" and the next blank line.
_trac0r_section_words() {
    printf '%s\n' "$1" | awk -v head="$2" '
        $0 == head { on = 1; next }
        on && /^[ \t]*$/ { exit }
        on && /^  [a-z]/ { print $1 }'
}

# Options in a help text, "--name METAVAR" or "--name" per line: from the option lines
# (indented by one to four spaces, starting with "-"), every "--name" with the word after it when that word
# is an upper-case metavariable.
_trac0r_options() {
    printf '%s\n' "$1" | awk '
        /^ ? ? ? ?-/ {
            line = $0
            sub(/^ +/, "", line)
            # The option column ends at the first run of two spaces.
            n = index(line, "   ")
            if (n > 0) line = substr(line, 1, n - 1)
            gsub(/,/, " ", line)
            k = split(line, w, " ")
            for (i = 1; i <= k; i++) {
                if (w[i] ~ /^--[a-z]/) {
                    if (i < k && w[i + 1] ~ /^[A-Z][A-Z]*$/) print w[i], w[i + 1]
                    else print w[i]
                }
            }
        }'
}

# The names listed under an option in the help: lines indented deeper than the option's
# text that start with a lower-case word followed by two spaces ("  pt      next-event").
_trac0r_option_names() {
    printf '%s\n' "$1" | awk -v opt="$2" '
        /^ ? ? ? ?-/ && on { exit }
        /^ ? ? ? ?-/ && index($0, " " opt " ") > 0 { on = 1; next }
        on && /^                    +[a-z][a-z0-9]*  / { print $1 }'
}

_trac0r() {
    # The words up to the cursor, split at blanks only: readline also splits at ':' and
    # '=' (COMP_WORDBREAKS), which would cut "builtin:cornell" and "--out=FILE" apart.
    local line=${COMP_LINE:0:COMP_POINT} words cword cur prev prog
    read -ra words <<<"$line"
    if [ -z "$line" ] || [ "${line%[[:space:]]}" != "$line" ]; then
        words+=("")
    fi
    cword=$((${#words[@]} - 1))
    cur=${words[cword]}
    prev=
    if [ "$cword" -gt 0 ]; then
        prev=${words[cword - 1]}
    fi
    prog=${words[0]}
    COMPREPLY=()

    local top
    if [ "$cword" -eq 1 ]; then
        top=$(_trac0r_help "$prog")
        mapfile -t COMPREPLY < <(compgen -W "$(_trac0r_section_words "$top" "Commands:")
            $(_trac0r_options "$top" | awk '{ print $1 }')" -- "$cur")
        return 0
    fi

    local cmd=${words[1]} help
    help=$(_trac0r_help "$prog" "$cmd")
    if [ "$cmd" = bench ]; then
        if [ "$cword" -eq 2 ]; then
            mapfile -t COMPREPLY < <(compgen -W "$(_trac0r_section_words "$help" "Benchmarks:")
                $(_trac0r_options "$help" | awk '{ print $1 }')" -- "$cur")
            return 0
        fi
        help=$(_trac0r_help "$prog" bench "${words[2]}")
    fi
    [ -n "$help" ] || return 0

    # The value of an option that takes one, as the next word or after '='.
    local options meta opt=$prev value=$cur
    options=$(_trac0r_options "$help")
    case $cur in
        --*=*)
            opt=${cur%%=*}
            value=${cur#*=}
            ;;
    esac
    meta=$(printf '%s\n' "$options" | awk -v o="$opt" '$1 == o { print $2; exit }')
    if [ -n "$meta" ] || [ "$opt" != "$prev" ]; then
        local names
        case $meta in
            FILE | PREFIX)
                mapfile -t COMPREPLY < <(compgen -f -- "$value")
                ;;
            DIR)
                mapfile -t COMPREPLY < <(compgen -d -- "$value")
                ;;
            SCENE)
                mapfile -t COMPREPLY < <(
                    compgen -W "$(printf '%s\n' "$help" | grep -o 'builtin:[a-z-]*[a-z]' | sort -u)" -- "$value"
                    compgen -f -X '!*.json' -- "$value"
                    compgen -d -- "$value")
                ;;
            NAME)
                names=$(_trac0r_option_names "$help" "$opt")
                mapfile -t COMPREPLY < <(compgen -W "$names" -- "$value")
                ;;
            DEV)
                mapfile -t COMPREPLY < <(compgen -W "cpu opencl" -- "$value")
                ;;
        esac
    else
        case $cur in
            -*)
                mapfile -t COMPREPLY < <(compgen -W "$(printf '%s\n' "$options" | awk '{ print $1 }')" -- "$cur")
                ;;
            *)
                # Positional arguments: scenes for render, view and info; images for compare.
                case $cmd in
                    render | view | info | bench)
                        mapfile -t COMPREPLY < <(compgen -f -X '!*.json' -- "$cur"; compgen -d -- "$cur")
                        ;;
                    compare)
                        mapfile -t COMPREPLY < <(compgen -f -X '!*.png' -- "$cur"
                            compgen -f -X '!*.pfm' -- "$cur"
                            compgen -d -- "$cur")
                        ;;
                esac
                ;;
        esac
    fi
    # Readline replaces only the part of the word after its last ':' or '='.
    local cut=${cur%"${cur##*[:=]}"}
    if [ -n "$cut" ] && [ ${#COMPREPLY[@]} -gt 0 ]; then
        if [ "$opt" != "$prev" ]; then
            COMPREPLY=("${COMPREPLY[@]/#/$opt=}")
        fi
        COMPREPLY=("${COMPREPLY[@]#"$cut"}")
    fi
    return 0
}
complete -F _trac0r -o filenames trac0r
