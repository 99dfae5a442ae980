#!/bin/bash
# usage: runone.sh NAME ARGS... ; runs `rrtdrive simulate ARGS --json R/NAME.json`, saves the printed summary and exit code in R/NAME.txt
R=/work/main/results/docs_s24
name=$1; shift
{ echo "# cd /tmp/s24/docs && rrtdrive simulate $* --json results/docs_s24/$name.json"; rrtdrive simulate "$@" --json $R/$name.json 2>&1; echo "exit $?"; } > $R/$name.txt
