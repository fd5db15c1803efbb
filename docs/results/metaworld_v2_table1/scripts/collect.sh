#!/bin/sh
# Issue 46: the finished jobs of the Meta-World v2 Table 1 sweep (frozen checkout /work/run-tree9) into
# docs/results/metaworld_v2_table1/jobs, then its report (version 1's collect script, given v2's folders), then its rows
# into docs/results/README.md.
sh /work/main/docs/results/metaworld_table1/scripts/collect.sh /work/run-tree9/runs/multirun/metaworld_v2_table1 docs/results/metaworld_v2_table1
python docs/results/metaworld_v2_table1/scripts/paste_rows.py docs/results/metaworld_v2_table1/table1.md "### Version 2: timing a fixed pattern cannot follow"
