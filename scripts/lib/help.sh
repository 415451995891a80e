# Sourced by the scripts, first thing (before they change folder): their --help, which is the comment block at
# the top of the script, and the refusal of an argument a script does not take.
ph_script=$(realpath "$0")

# Prints the calling script's header comment, without the "# ".
print_help() { sed -n '2,/^[^#]/{/^#/s/^# \{0,1\}//p}' "$ph_script"; }

# For a script that takes no argument: answers --help, refuses anything else (before any work is done).
no_arguments() {
  case "${1:-}" in
    "") ;;
    -h | --help) print_help; exit 0 ;;
    *) echo "$(basename "$ph_script"): unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
}
