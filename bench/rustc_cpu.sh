#!/usr/bin/env bash
# CPU time of every rustc invocation of a build, by crate: a RUSTC_WRAPPER.
#
#   RUSTC_WRAPPER=bench/rustc_cpu.sh RUSTC_CPU_LOG=/tmp/rustc-cpu.log cargo build --locked
#
# appends one line per compilation to the log: user and system CPU seconds, the crate's name,
# its crate types and the opt-level Cargo gave it (empty for opt-level 0). Summed by group, it
# says where a cold build's CPU goes (BENCHMARKS.md, "The README's two commands, cold: where the
# CPU goes, by crate"). Build scripts' runs and the linker's own processes are not counted.
set -u
rustc=$1
shift
name=unknown types="" opt=""
previous=""
for argument in "$@"; do
    case $previous in
    --crate-name) name=$argument ;;
    --crate-type) types="$types$argument," ;;
    esac
    case $argument in
    opt-level=*) opt=$argument ;;
    --test) types="${types}test," ;;
    esac
    previous=$argument
done
times=$(mktemp)
/usr/bin/time -f "%U %S" -o "$times" "$rustc" "$@"
status=$?
echo "$(tail -n 1 "$times") $name $types $opt" >>"${RUSTC_CPU_LOG:-/tmp/rustc-cpu.log}"
rm -f "$times"
exit $status
