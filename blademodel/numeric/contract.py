"""The kernel contract: status codes, counters and run-buffer layout shared by every kernel.

Both kernels (:mod:`.loop`, the product-mode kernel, and :mod:`.contact_loop`, the
per-contact kernel) and their Python drivers use these names; nothing indexes a
counter or tests a status by a bare number. The template files are pasted into
generated modules, so they import these constants by name from here.
"""

#: ``integrate`` finished the requested periods.
STATUS_OK = 0
#: A state became non-finite (NaN or inf).
STATUS_NONFINITE = 1
#: More events than ``max_events`` within one step.
STATUS_EVENT_STORM = 2
#: The friction complementarity problem of an event was not resolved within its pivot cap.
STATUS_FRICTION_UNRESOLVED = 3
#: A tangent replay (:mod:`.tangent_loop`) took another transition than the kernel's event log.
STATUS_REPLAY_MISMATCH = 4
#: A tangent replay met an event whose guard has a zero rate along the flow (no saltation matrix).
STATUS_GRAZING_EVENT = 5

#: Human-readable status names, by code.
STATUS_NAMES = {STATUS_OK: "done", STATUS_NONFINITE: "non-finite state", STATUS_EVENT_STORM: "event storm",
                STATUS_FRICTION_UNRESOLVED: "friction problem unresolved",
                STATUS_REPLAY_MISMATCH: "tangent replay left the logged events",
                STATUS_GRAZING_EVENT: "grazing event (no saltation matrix)"}

# Integer counters: one int64 array of N_COUNTERS, accumulated across calls of ``integrate``.
C_STEPS = 0           #: completed RK4 steps
C_EVENTS = 1          #: events handled (guard transitions and friction-problem mode changes)
C_LOCATION_SUBSTEPS = 2      #: sub-steps spent locating events
C_RHS = 3             #: right-hand-side evaluations
C_LOGGED = 4          #: events offered to the log (may exceed its length)
C_RECORDS = 5         #: records written (the next record's row)
C_FRICTION_PIVOTS = 6  #: pivots of the friction complementarity problem (per-contact kernel)
C_GRAZING = 7         #: crossings found inside a step whose ends showed none (per-contact kernel)
C_CLUSTERS = 8        #: clusters stepped through their events (per-contact kernel)
C_RESTARTS = 9        #: steps begun again because a contact on a cluster's boundary crossed (per-contact kernel)
N_COUNTERS = 10

#: Names of the integer counters, in index order (``SimulationResult.counters``).
COUNTER_NAMES = ("steps", "events", "location_substeps", "rhs_evaluations", "events_logged", "records",
                 "friction_pivots", "grazing_events", "clusters", "cluster_restarts")

# Float statistics: one float64 array of N_STATS, accumulated across calls.
S_MAX_CONE_RATIO = 0  #: largest ``|f| / (mu N)`` over sticking rigid-stick contacts at step ends
N_STATS = 1

#: Names of the float statistics, in index order.
STAT_NAMES = ("max_cone_ratio",)

# ---- the per-contact kernel's run buffer --------------------------------------------------
# The per-contact kernel takes its tables and work arrays as four flat arrays, ``I``
# (int64) and ``R`` (float64) for the model, ``WI`` and ``WF`` for work, because a
# compiled call passes each array as a struct of 7 to 9 words: with the tables as
# 40 separate arrays a call cost about 0.6 us. The header of ``I`` gives the sizes and
# the offset of every table (``blademodel.numeric.contact_kernel.pack_tables``).
H_N = 0        #: number of coordinates n
H_NC = 1       #: number of contacts nc
H_NF = 2       #: forcing entries
H_NG = 3       #: frequency groups
H_LPW = 4      #: columns of the law parameter-index table
H_NLAW = 5     #: law states in all (after q and u)
H_NS = 6       #: stages of the stepping method's tableau (0: classical RK4, written out)
O_KP, O_KI, O_CP, O_CI, O_FI, O_FG, O_CIDX, O_CLAW, O_CSO, O_LP, O_WP, O_WI = range(7, 19)   #: offsets into I
R_INVM, R_KV, R_CV, R_FS, R_FC, R_OM, R_GN, R_GR, R_GAP, R_K, R_P, R_W, R_RK = range(19, 32)  #: offsets into R
(F_F, F_N, F_ND, F_V, F_FR, F_DL, F_X, F_D, F_NULL, F_B, F_SG, F_CG, F_Z, F_YEV, F_L, F_DR,
 F_T, F_FD, F_XD) = range(32, 51)  #: offsets into WF
#: Each contact's normal law (``I``): NK_SPRING ``N = k delta``, NK_DAMPED ``N = k delta + c ddelta/dt``
#: (opens at ``N = 0``), NK_LOAD ``N = N0`` (never opens); and its values (``R``): ``c``, ``N0``.
O_CNK, R_CC, R_N0 = 51, 52, 53
NK_SPRING, NK_DAMPED, NK_LOAD = 0, 1, 2
#: Locality (``I``): the forcing entries of each coordinate (CSR ``Fp`` over ``fi``, which is sorted by
#: coordinate), the contacts touching each coordinate (CSR ``Dp``, ``Di``), the coordinates coupled to
#: each by a spring or damper (CSR ``Ap``, ``Ai``: the symmetric sparsity of ``K`` and ``C``); and (``WF``)
#: the energy accumulators' increments of a cluster's first sub-step.
O_FP, O_DP, O_DI, O_AP, O_AI, F_ACC = 54, 55, 56, 57, 58, 59
#: (``WF``) the guard offsets of the contacts marked ``WC_NEAR``, ``GMAX`` per contact; the time of each
#: contact's last change of mode (NaN: none in this run); until when a suspect's crossings are noise.
F_GOFF, F_TLAST, F_NOISE = 60, 61, 62
#: (``R``) the forcing's phase table: ``R_TG`` holds ``(hh, 1 / hh, M)``, the half step ``hh = period /
#: (2 steps_per_period)`` and the table's length ``M = 2 steps_per_period`` (0: no table); ``R_TAB`` the sin
#: and cos of every frequency group at the half-step times of one period, ``(sin, cos)`` pairs, group by
#: group (``forcing_phase``).
R_TG, R_TAB = 63, 64
H_SIZE = 65    #: header length
#: A time within this many units in the last place of a half-step time ``k hh`` reads the phase table.
SNAP_ULPS = 8.0
#: Rows of the kernel's stage buffer ``SC`` before the extra stages of a tableau method
#: (row ``SC_Y0``: the state at the start of a step whose events are being handled).
SC_ROWS = 10
SC_Y0 = 9
#: Rows of the guard buffer ``GS`` (rows 9 and 10 keep the guards and rates at the start of a step
#: whose events are being handled).
GS_ROWS = 11

# ---- the per-contact kernel's integer work array ``WI`` -----------------------------------
# A header, then per-contact arrays (``nc`` each), per-coordinate arrays (``n`` each) and the
# active state rows (``n_state``); the template's views ``wvec``, ``wdof`` and ``wrow`` take them.
W_NS = 0       #: sticking rigid contacts, all clusters
W_NULL = 1     #: the contact with the stick factor's zero pivot (a closed ring that sticks), or -1
W_FULL = 2     #: 1: the active set is the whole model; 0: the cluster in ``WC_AC``, ``WD_AD``, the rows
W_ND = 3       #: active coordinates (a cluster's)
W_NCA = 4      #: active contacts (a cluster's)
W_NSA = 5      #: active state rows (a cluster's)
W_STAMP = 6    #: the last cluster's stamp (``WC_MARK``, ``WD_MARK``)
W_NB = 7       #: contacts on the boundary of this step's clusters (``WC_BL``)
W_NEV = 8      #: events handled in the current step (all clusters)
W_NNEAR = 9    #: contacts marked in ``WC_NEAR``
W_HEAD = 10    #: header length
#: Per-contact arrays: sticking rigid contact (0/1), first column of its row of the stick factor's
#: envelope, contacts of the friction problem, modes before an event, modes before the friction
#: problem, the log row of its transition in the current event, the active contacts (a cluster's,
#: ascending), seeds of the step's clusters, cluster stamp (boundary: minus the stamp), modes at the
#: step's start, boundary contacts, every contact (``0 ... nc - 1``: the whole model's list), fired
#: before its own root (``first_near_crossing``): 1 + the mode it entered, whose guards are read
#: shifted by ``F_GOFF`` (``guard_offsets``); 0 if not.
#: Last, suspects of a sub-step (``mark_suspects``): contacts that changed mode just before its start and
#: whose guards did not cross over it: 1, and 2 while a crossing found in the bracket under test is rounding
#: noise (``suspects_at``).
WC_STK, WC_ENV, WC_U, WC_CM0, WC_BEFORE, WC_FIRED, WC_AC, WC_SEED, WC_MARK, WC_CMSTEP, WC_BL, WC_ALL, WC_NEAR, \
    WC_SUSPECT = range(14)
WC_COUNT = 14
#: Per-coordinate arrays: the active coordinates (a cluster's, in the order found), cluster stamp, every
#: coordinate (``0 ... n - 1``). The state rows follow: a cluster's, then every row.
WD_AD, WD_MARK, WD_ALL = 0, 1, 2
WD_COUNT = 3
#: Numba fixes up a negative index (``a[-1]``) on every array access whose index it cannot prove
#: non-negative, such as one read from an index table; the kernels mask such an index's sign bit
#: (``i & NONNEG``: a no-op on a valid index) so that the compiler sees it is not negative. On the
#: per-contact kernel's hot loops this saved about a quarter of the time.
NONNEG = 0x7FFFFFFFFFFFFFFF
#: Frequency groups and law states the work buffer holds.
MAX_GROUPS = 8
MAX_LAW_STATES = 64
