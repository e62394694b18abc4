# bash completion for rackcat. Subcommands and options come from rackcat's own --help
# (CLI11), so the completion follows the installed version without a list of its own.
_rackcat_help_words() {
  # $1: "" for the top level, else the subcommand. Prints options, or subcommands at the top.
  local cmd=${COMP_WORDS[0]}
  if [[ -z $1 ]]; then
    "$cmd" --help 2>/dev/null | awk '/^Subcommands:/{s=1; next} s && /^  [a-z]/{print $1}'
  else
    "$cmd" "$1" --help 2>/dev/null | grep -oE '(^|[ ,])--?[A-Za-z][-A-Za-z0-9]*' | tr -d ' ,'
    "$cmd" "$1" --help 2>/dev/null | awk '/^Subcommands:/{s=1; next} s && /^  [a-z]/{print $1}'
  fi
}

_rackcat() {
  local cur prev sub i
  cur=${COMP_WORDS[COMP_CWORD]}
  prev=${COMP_WORDS[COMP_CWORD-1]}
  sub=""
  for ((i = 1; i < COMP_CWORD; i++)); do
    if [[ ${COMP_WORDS[i]} != -* ]]; then
      sub=${COMP_WORDS[i]}
      break
    fi
  done
  case $prev in
    --config|--pcap|--state-dir|--output|-o|--line|--eni|--data-dir|--token-file)
      COMPREPLY=($(compgen -f -- "$cur"))
      return
      ;;
    --esi-dir)
      COMPREPLY=($(compgen -d -- "$cur"))
      return
      ;;
    --iface|--rim-bus)
      COMPREPLY=($(compgen -W "$(ls /sys/class/net 2>/dev/null)" -- "$cur"))
      return
      ;;
  esac
  if [[ -z $sub ]]; then
    COMPREPLY=($(compgen -W "$(_rackcat_help_words "") --help --version" -- "$cur"))
  elif [[ $cur == -* ]]; then
    COMPREPLY=($(compgen -W "$(_rackcat_help_words "$sub")" -- "$cur"))
  else
    COMPREPLY=($(compgen -f -- "$cur"))
  fi
}
complete -F _rackcat rackcat
