#!/bin/sh
# Issue 46: the finished jobs of the Meta-World v2 Table 1 sweep (frozen checkout /work/run-tree9) into
# docs/results/metaworld_v2_table1/jobs, then its report (version 1's collect script, given v2's folders).
sh /work/main/docs/results/metaworld_table1/scripts/collect.sh /work/run-tree9/runs/multirun/metaworld_v2_table1 docs/results/metaworld_v2_table1
