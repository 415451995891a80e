# Sourced by the scripts, first thing (before they change folder): their --help, which is the comment block at
# the top of the script, and the refusal of an argument a script does not take.
ph_script=$(realpath "$0")

# Prints the calling script's header comment, without the "# ".
print_help() { sed -n '2,/^[^#]/{/^#/s/^# \{0,1\}//p}' "$ph_script"; }

# For a script that takes no argument: answers --help, refuses anything else (before any work is done).
no_arguments() {
  [ $# -gt 0 ] || return 0
  case "$1" in
    -h | --help) [ $# -eq 1 ] && { print_help; exit 0; } ;;
  esac
  echo "$(basename "$ph_script"): unknown argument '$1' (try --help)" >&2
  exit 2
}

# For a script that takes one option at most: refuses a second argument (before any work is done), which would
# otherwise be ignored without a word.
one_argument_at_most() {
  [ $# -le 1 ] || { echo "$(basename "$ph_script"): one argument at most, not '$*' (try --help)" >&2; exit 2; }
}
