# Footprint budgets of the Cortex-M4F build (Release, -O2), checked by
# cmake/footprint.cmake: a change that exceeds one fails the cross test, so
# growth is a decision (raise the budget here, in the same commit, and say
# why), not an accident. Each is the value measured when it was set plus a
# margin of about 10 % (docs/footprint.md has the measurements).

# libhstpf.a flash (code + rodata + data, all objects), bytes; 70 100 measured
# (59 544 when first set at 64 000; raised in the fourteenth session for
# refine = 2's grid hypothesis, which took it from 62 136 to about 63 700;
# raised to 77 000 in the twentieth session: the nineteenth's density update
# of the rows' filters, kalman_fix.c, and placing again a filter that lost
# the train, a fix for a valid position published 806 m off, took it past
# 70 000; raised to 85 000 in the twenty-sixth session: the Kalman engine's
# stop (kalman_rest.c) and the traction check (traction_check.c), a fix for
# a traction with its sign swapped driving every model the wrong way, took
# it to 77 100; raised to 88 000 in the twenty-ninth session: the run rule
# for steps in the fixes under a heavy-tailed noise (fix_step.c) and each
# engine's spread of a step's variance over its cells or particles, a fix
# for a train at a platform published moving off at 0.6-2.4 m/s, took it
# from 83 568 to 86 924; raised to 91 000 in the thirty-first session: the
# Kalman rows' unclamped speed while stopping (kalman_rest.c), a fix for
# 0 +- 0 m/s published while the train still rolled into a stop, and the
# speed prior's confirmation (bank.c), a fix for a unit started at 300 km/h
# publishing 0 +- 1 m/s valid, took it from 87 592 to 89 084; 89 540 at the
# session's end)
set(HSTPF_BUDGET_FLASH 91000)
# libhstpf.a static RAM (data + bss), bytes: the library keeps no state
set(HSTPF_BUDGET_LIB_RAM 0)
# An instance per engine and capacity (models x particles; grid 20 x 72),
# bytes: sizeof(hstpf_t) plus the workspace that engine needs at those
# capacities (HSTPF_PARTICLE_WS_BYTES, HSTPF_GRID_WS_BYTES; the Kalman
# engine needs none; the grid's with the continuous hypothesis' grid, what
# the defaults need under non-Gaussian process noise). docs/footprint.md,
# "Instance size". Lowered in the fifteenth session, when the process
# noises stopped keeping a density table (6 288 B less per instance).
set(HSTPF_BUDGET_KALMAN_3x100 14600)       # 13 352 measured (twenty-fifth session)
set(HSTPF_BUDGET_KALMAN_17x100 17400)      # 16 016
set(HSTPF_BUDGET_KALMAN_17x256 17400)      # 16 016 (library default)
set(HSTPF_BUDGET_KALMAN_17x1000 17400)     # 16 016
set(HSTPF_BUDGET_PARTICLE_3x100 20100)     # 18 352
set(HSTPF_BUDGET_PARTICLE_17x100 41300)    # 37 816
set(HSTPF_BUDGET_PARTICLE_17x256 78700)    # 71 824
set(HSTPF_BUDGET_PARTICLE_17x1000 257100)  # 234 016
set(HSTPF_BUDGET_GRID_3x100 49152)         # 48 328; issue 13's bar, 48 KiB, not +10 %
set(HSTPF_BUDGET_GRID_17x100 145700)       # 132 752
set(HSTPF_BUDGET_GRID_17x256 145700)       # 132 752
set(HSTPF_BUDGET_GRID_17x1000 145700)      # 132 752
# lowered in the twenty-sixth session: the hypothesis' covariance step in
# place (refine.c, propagate) took hstpf_step from 1 184 to 1 052 B
set(HSTPF_BUDGET_STACK_STEP 1160)     # 1 060 (twenty-sixth session)
set(HSTPF_BUDGET_STACK_INIT 880)      # 808
set(HSTPF_BUDGET_STACK_ESTIMATE 900)  # 840 (808 before refine = 2)
# stack measured on QEMU (painted, with libm and run-time helpers), bytes
# raised to 1 280 in the thirty-first session when the Kalman stop's
# unclamped speed took it to 1 224, and back to 1 180 after bank.c's split
# measured 1 104
set(HSTPF_BUDGET_STACK_STEP_MEASURED 1180) # 1 104 (thirty-first session; 1 096 in the twenty-sixth)
# instructions on the target (QEMU -icount), Case 1, 3 models
set(HSTPF_BUDGET_INSTR_PARTICLE_STEP 520)  # 471.0 per particle-step
# raised in the twenty-sixth session: the traction check's shadow filter, a
# 2 x 2 Kalman step in double per bank step (27 000 instructions; 46 183 per
# model-step before it, 44 013 when the budget was set)
set(HSTPF_BUDGET_INSTR_KALMAN_MODEL 61000) # 55 151 per model-step
set(HSTPF_BUDGET_INSTR_GRID_MODEL 895000)  # 743 224 per model-step (20 x 72, refine on, speed lattice on; 779 714 without it, 799 666 before the twelfth session, 809 231 before the moments in float, 882 849 before the kernels were cut at the box's tail, 1 210 420 at 48 x 48)
set(HSTPF_BUDGET_INSTR_GRID_MODEL_CASE2 893000)  # 811 954 per grid model-step (paper Case 2 inputs, 3 rows and the hypothesis' grid; first measured in the fifteenth session)
# a 17-row grid bank step with the defaults (Student-t fixes, Gaussian
# process noise: grid_rows = 3 rows on the grid, the others on Kalman
# filters that score each fix by its density): issue 13's bar, 3 M, not
# +10 % (2.60 M in the eighteenth session on Gaussian fixes, 2.74 M in the
# nineteenth on Student-t fixes)
set(HSTPF_BUDGET_INSTR_GRID_17ROW_STEP 3000000)
