"""What the C runtime and Python must agree on, stated once (DESIGN.md §4, §7).

Plain data, no SymPy: the per-position status codes with the typed error each becomes, the options struct,
the kernel signatures (one per kernel kind), the mechanism descriptor's fields and the runtime's exported
functions. :mod:`sewgen.derive.abi_header` writes them into ``sg_abi.h`` (read by csrc/sg_runtime.h and every
generated kernel file) and ``sg_abi.cdef`` (read by cffi); the generated kernels take their prototypes from
:data:`KERNELS`, and :mod:`sewgen.mechanism` maps a failing position's code to its error through
:func:`error_for`. Nothing here is repeated by hand anywhere else.
"""
from __future__ import annotations

from sewgen import errors


#: (C enumerator, code, error class or None, meaning), in code order.
STATUS = (
    ("SG_OK", 0, None, "solved"),
    ("SG_CANNOT_ASSEMBLE", 1, errors.AssemblyError,
     "the loop does not close at this input (a dyad's circles do not meet)"),
    ("SG_SINGULAR", 2, errors.SingularPositionError,
     "the constraint Jacobian or a force block is singular here (toggle / dead-centre position)"),
    ("SG_BRANCH_JUMP", 3, errors.BranchJumpError,
     "the declared assembly branch cannot be continued here: Newton, in steps down to 1e-6 rad, finds only "
     "positions where a closing loop's orientation sign differs from the sweep's first position"),
    ("SG_NAN_INPUT", 4, None, "a shaft angle, speed or acceleration is not finite (Python checks first)"),
    ("SG_NO_CONVERGENCE", 5, errors.ConvergenceError, "Newton ran out of iterations"),
    ("SG_NONFINITE", 6, errors.NonFiniteResultError,
     "a result came out non-finite (the motion kernel tests every output)"),
    ("SG_BAD_ARGUMENT", 7, None, "sizes or options out of range: nothing was computed"),
    ("SG_BAD_DESIGN", 8, None,
     "batched designs: a design's parameter or held input is not finite or out of range, a branch sign is not "
     "+1 or -1, or a dimension derived from its parameters is not real; the design is skipped (Python names "
     "the parameter)"),
    ("SG_FRICTION_LOCK", 9, errors.FrictionLockError,
     "Coulomb friction does not settle: the friction loads, iterated with the reactions, do not converge in the "
     "kernel's iterations (a joint at or near self-locking, as a slide whose friction outgrows its drive)"),
)

_ERRORS = {code: cls for _, code, cls, _ in STATUS}
_NAMES = {code: name for name, code, _, _ in STATUS}


def error_for(code: int):
    """The :class:`~sewgen.errors.PositionError` subclass of a status code; None for codes Python prevents."""
    return _ERRORS.get(code)


def status_name(code: int) -> str:
    return _NAMES.get(code, f"unknown status {code}")


#: The runtime's fixed sizes (C name, value, meaning): its stack work arrays are this large, so the derivation
#: refuses a mechanism past them and Python reads them from here.
LIMITS = (
    ("SG_MAX_Q", 48, "largest number of coordinates, and largest LU (force blocks included), of a mechanism"),
    ("SG_MAX_C", 2048, "largest number of constants a mechanism's kernels hoist out of its parameters"),
    ("SG_MAX_GROUP", 4096, "largest number of groups of observables a sweep computes selectively (more: the "
                           "joint motion kernel)"),
    ("SG_MAX_LOAD", 512, "largest number of load slots per position"),
    ("SG_MAX_DIRECT", 64, "largest number of columns a SIMD sweep writes straight to their own arrays (more: "
                          "rows, then copies)"),
    ("SG_BLOCK", 8, "positions a Newton sweep predicts from one history and solves as a block, in every loop and "
                    "at every SIMD level (the scalar and the SIMD loops give the same values)"),
    ("SG_HISTORY", 5, "solved states a Newton sweep's predictor extrapolates from (a Lagrange polynomial of "
                      "degree 4 at most)"),
    ("SG_NCOND", 3, "numbers a motion or rates kernel writes to cond, the rates' error estimate's (csrc/sg_runtime.h "
                    "sg_rates_error)"),
)
LIMIT = {name: value for name, value, _ in LIMITS}

#: Per-design reductions of sg_sweep_designs, in the C numbering (enum sg_reduction): (C name, Python name).
REDUCTIONS = (("SG_RED_MIN", "min"), ("SG_RED_MAX", "max"), ("SG_RED_ABSMAX", "absmax"), ("SG_RED_RMS", "rms"),
              ("SG_RED_MEAN", "mean"))

#: Fields of ``sg_options`` (C type, name, meaning).
OPTIONS = (
    ("double", "tol", "relative loop residual tolerance: Newton stops when every closure equation's residual is "
                      "below tol times that equation's own loop size (kernel 'scales')"),
    ("int", "max_iter", "Newton iterations per position"),
    ("int", "newton_only", "1: Newton even where a closed form exists (tests, benchmarks)"),
    ("double", "singular_tol", "largest estimated relative error of the velocities and accelerations; a position "
                               "above it is SG_SINGULAR unless keep_singular"),
    ("int", "keep_singular", "1: positions above singular_tol keep their results (status SG_OK, err says why)"),
    ("int", "generic", "1: the closed-form loop with the kernels called through the descriptor (csrc/sg_runtime.h "
                       "sg_closed_sweep) rather than the mechanism's inlined copy (tests: the two agree to the bit)"),
    ("int", "scalar", "1: the scalar loop even where the mechanism has a SIMD one and the CPU runs it (a closed "
                      "form: SG_LANES positions at a time; Newton: the solved positions' rates, observables and "
                      "forces SG_LANES at a time) (tests: the two agree to rounding, with the same statuses)"),
)

#: Fields of ``sg_request`` (C type, name, meaning): one sweep's arrays and settings, what every entry point that
#: sweeps (sg_sweep, sg_solve_lean, sg_sweep_designs) reads in place of a long argument list. Python fills one
#: per prepared call (sewgen.engine.mechanism.Sweep.request); a field an entry point does not read is left 0.
REQUEST = (
    ("size_t", "n", "shaft positions"),
    ("const double *", "phi", "shaft angles (n), rad"),
    ("const double *", "omega", "shaft speed at each position (n), rad/s"),
    ("const double *", "alpha", "shaft acceleration at each position (n), rad/s^2"),
    ("double", "speed", "sg_solve_lean: the one shaft speed (omega and alpha are written into blk)"),
    ("const double *", "held", "held inputs (nx - 1; sg_sweep_designs: nd rows)"),
    ("const double *", "p", "parameters (np; sg_sweep_designs: nd rows)"),
    ("const int *", "branch", "branch signs (nbranch; sg_sweep_designs: nd rows)"),
    ("const double *", "q_guess", "Newton's start where no closed form exists (nq)"),
    ("const sg_options *", "opt", "the options"),
    ("const size_t *", "order", "the order the positions are solved in (a permutation sorting phi), or NULL: as "
                                "given (sg_solve_lean: phi must then ascend)"),
    ("const double *", "gv", "gravity (2) for the forces; NULL: kinematics only"),
    ("const double *", "loads", "load slots (n x nload), or NULL"),
    ("double *", "q", "out: coordinates (n x nq)"),
    ("double *", "qd", "out: their velocities (n x nq)"),
    ("double *", "qdd", "out: their accelerations (n x nq)"),
    ("double *", "obs", "out: observables (n x nobs)"),
    ("double *", "err", "out: each position's estimated relative error of the rates (n), or NULL"),
    ("double *", "frc", "out: force outputs (n x nfo) where gv is given"),
    ("int *", "status", "out: each position's status (n); sg_solve_lean: NULL puts them at blk's tail"),
    ("int", "nqa", "sg_solve_lean: how many angle coordinates to make continuous"),
    ("const int *", "qcols", "sg_solve_lean: their columns of q"),
    ("int", "noa", "sg_solve_lean: how many angle observables to make continuous"),
    ("const int *", "ocols", "sg_solve_lean: their columns of obs"),
    ("double *", "blk", "sg_solve_lean: one block for phi, omega, alpha, err, q, qd, qdd, obs (n rows each), then "
                        "frc where gv is given"),
    ("size_t", "nd", "sg_sweep_designs: designs"),
    ("int", "ncheck", "sg_sweep_designs: the first ncheck constants must be finite"),
    ("int", "nangle", "sg_sweep_designs: how many flat columns are angles made continuous"),
    ("const int *", "angle_cols", "sg_sweep_designs: those columns"),
    ("int", "nsel", "sg_sweep_designs: how many flat columns are kept"),
    ("const int *", "sel", "sg_sweep_designs: those columns"),
    ("double *", "out", "sg_sweep_designs: out[k*out_stride + d*n + i], NaN for a failed design"),
    ("size_t", "out_stride", "sg_sweep_designs: the stride of out between selected columns"),
    ("int", "nred", "sg_sweep_designs: how many reductions"),
    ("const int *", "red", "sg_sweep_designs: nred x 3: kind (enum sg_reduction), column, second column for the "
                           "norm of two or -1"),
    ("double *", "red_val", "sg_sweep_designs: red_val[k*red_stride + d], NaN for a failed design"),
    ("long long *", "red_idx", "sg_sweep_designs: the extremum's first position in the caller's order (-1 for "
                               "rms, mean, a failed design)"),
    ("size_t", "red_stride", "sg_sweep_designs: the stride of red_val and red_idx"),
    ("double *", "work", "sg_sweep_designs: scratch of one design's sweep, n*(3nq+nobs+3) doubles"),
    ("int *", "work_status", "sg_sweep_designs: scratch statuses (n)"),
    ("int *", "design_status", "sg_sweep_designs: in: nonzero skips the design; out: the status of its first "
                               "failing position, or SG_BAD_DESIGN (nd)"),
    ("long long *", "first_bad", "sg_sweep_designs: each design's first failing position, -1 for none (nd)"),
    ("long long *", "nbad", "sg_sweep_designs: positions failing with that status (nd), or NULL"),
    ("long long *", "last_bad", "sg_sweep_designs: the last of them (nd), or NULL"),
    ("const unsigned char *", "want", "the runtime's own (sg_sweep_designs' selected outputs; NULL: every "
                                      "observable): the ngroup groups of observables a kinematic sweep computes "
                                      "(kernels 'rates' and 'observe'), then whether the caller reads the "
                                      "coordinates (want[ngroup])"),
    ("const double *", "trig", "the runtime's own (NULL: computed): the shaft angles' cos (n) then sin (n) as the "
                               "SIMD loop's vector math gives them (sg_sweep_designs: once for every design)"),
    ("struct sg_columns *", "cols", "the runtime's own (NULL: none; csrc/sg_runtime.h): columns the SIMD loop "
                                    "writes straight to their own arrays, setting cols->written, where q, qd, qdd "
                                    "and obs then hold only the rows its scalar steps wrote"),
)

# Kernel arguments: q coordinates; cq[2i], cq[2i+1] = cos, sin of angle coordinate i; x inputs and cx their
# cos, sin likewise; c the constants that sg_<m>_constants hoisted out of the parameters p.
_Q = (("const double *", "q"), ("const double *", "cq"), ("const double *", "x"), ("const double *", "cx"))

#: Kernel kinds: kind -> (return type, arguments (C type, name), meaning). The generated function of kind k of
#: mechanism m is ``sg_<m>_<k>``; the descriptor holds a pointer of type ``sg_<k>_fn`` to it.
KERNELS = {
    "constants": ("void", (("const double *", "p"), ("double *", "c")),
                  "every parameter-only subexpression, once per sweep"),
    "closed": ("int", (("const double *", "x"), ("const double *", "cx"), ("const double *", "c"),
                       ("const int *", "branch"), ("double *", "q"), ("double *", "cq"), ("double *", "err")),
               "the dyad chain in closed form, and err: the largest error of an angle coordinate (rad) and the "
               "product of the dyads' amplifications, as they bound them (csrc/sg_runtime.h sg_dyad_*); NULL in the "
               "descriptor where the loops do not split"),
    "residual": ("void", _Q + (("const double *", "c"), ("double *", "r"), ("double *", "jac")),
                 "loop-closure residual and its Jacobian dPhi/dq (row-major)"),
    "motion": ("int", _Q + (("const double *", "xd"), ("const double *", "xdd"), ("const double *", "c"),
                            ("double *", "qd"), ("double *", "qdd"), ("double *", "obs"), ("double *", "cond")),
               "velocities, accelerations and observables at a solved position; cond: the three numbers of the "
               "rates' error estimate (csrc/sg_runtime.h sg_rates_error): the condition number (inf norm) of dPhi/dq "
               "with each row over its loop's size (kernel 'scales') and its columns equilibrated, the share of the "
               "accelerations' centripetal and Coriolis terms in their scale, and the largest column factor of an "
               "angle coordinate"),
    "rates": ("int", _Q + (("const double *", "xd"), ("const double *", "xdd"), ("const double *", "c"),
                           ("double *", "qd"), ("double *", "qdd"), ("double *", "cond")),
              "the motion kernel without its observables: velocities, accelerations and cond, equal to the bit "
              "(a sweep that keeps a few outputs adds only their groups, kernel 'observe')"),
    "observe": ("int", _Q + (("const double *", "xd"), ("const double *", "xdd"), ("const double *", "c"),
                             ("const double *", "qd"), ("const double *", "qdd"), ("int", "group"),
                             ("double *", "obs")),
                "one group of observables (a point's, a body's, a cam's arc: obs[group_start[group]] up to "
                "obs[group_start[group + 1]]) from a position and its rates, equal to the bit to the motion "
                "kernel's; SG_NONFINITE where one of them is not finite"),
    "forces": ("int", _Q + (("const double *", "xd"), ("const double *", "c"), ("const double *", "obs"),
                            ("const double *", "gv"), ("const double *", "ld"), ("double *", "out")),
               "joint reactions, driving torques, frame on parts, energies: reads obs, gravity gv[2], loads ld"),
    "force_matrix": ("void", _Q + (("const double *", "c"), ("const double *", "obs"), ("const double *", "gv"),
                                   ("const double *", "ld"), ("double *", "A"), ("double *", "b")),
                     "A (nf x nf, row-major) and b of A f = b, for inspection"),
    "scales": ("void", _Q + (("const double *", "c"), ("double *", "out")),
               "each closure equation's own loop size (m; 1 for an angle equation): Newton's per-equation scale"),
    "lu_factor": ("int", (("double *", "a"), ("int *", "piv")),
                  "Newton's LU of dPhi/dq in place (sg_lu_factor with n = nq a literal: its loops unrolled whole, "
                  "the same operations in the same order)"),
    "lu_solve": ("void", (("const double *", "lu"), ("const int *", "piv"), ("double *", "b")),
                 "solve with a factor of kernel 'lu_factor' (sg_lu_solve with n = nq a literal), b overwritten"),
    "blocks": ("void", (("const double *", "jac"), ("double *", "out")),
               "the normalised determinant of each diagonal block of dPhi/dq (sewgen.derive.branches): its sign "
               "is that closing loop's assembly branch"),
    "anchors": ("void", _Q + (("const double *", "c"), ("double *", "out")),
                "world x, y of every drawing anchor (manifest \"anchors\"), then the cam arcs' radius and world "
                "normal sector (manifest \"arcs\"): nanchor_out values, for pictures of any mechanism"),
}

#: Sweep loops a generated file instantiates with its own kernels inlined (csrc/sg_runtime.h): kind ->
#: (return type, arguments, meaning); the descriptor holds ``sg_<kind>_fn`` pointers to the file's static
#: ``sg_<m>_<kind>`` (NULL where the mechanism has none).
HOOKS = {
    "sweep": ("size_t", (("const struct sg_mechanism *", "m"), ("const sg_request *", "r")),
              "the closed-form sweep of the request r with the file's kernels inlined (csrc/sg_runtime.h "
              "sg_closed_sweep), kinematics and (r->frc not NULL) kinetostatics as sg_sweep; r->want, r->trig and "
              "r->cols as sg_request says (this loop computes its own cos, sin and writes rows only); NULL without "
              "a closed form"),
}
HOOKS["sweep_simd"] = (HOOKS["sweep"][0], HOOKS["sweep"][1],
                       "the same sweep SG_LANES positions at a time (csrc/sg_simd.h sgv_closed_sweep: 8 in AVX-512 "
                       "or 4 in AVX2, the build's level); NULL "
                       "where the build has no SIMD or the mechanism's kernels have no vector form")

HOOKS["finish_simd"] = ("int", (("const struct sg_mechanism *", "m"), ("struct sg_lanes *", "lanes"),
                                 ("const double *", "c"), ("const sg_options *", "opt"), ("const double *", "gv"),
                                 ("const double *", "loads"), ("double *", "qd"), ("double *", "qdd"),
                                 ("double *", "obs"), ("double *", "frc"), ("const unsigned char *", "want")),
                         "a Newton sweep's rates, observables and (frc not NULL) forces at up to SG_LANES solved "
                         "positions at once (csrc/sg_simd.h sgv_finish): their rows written, the "
                         "bit mask of the lanes it vouches for returned, each one's estimated error in lanes->est; "
                         "lanes NULL: 1 where it can finish this sweep's positions (forces: without friction only), "
                         "0 where the scalar loop must; NULL with a closed form, without SIMD in the build or "
                         "without a vector form")

HOOKS["newton_simd"] = ("int", (("const struct sg_mechanism *", "m"), ("struct sg_block *", "b"), ("int", "first"),
                                 ("const double *", "c"), ("const sg_options *", "opt"), ("const double *", "w")),
                         "Newton at SG_LANES positions of a block at once (csrc/sg_simd.h sgv_newton): "
                         "lanes first.. of b, each started from its prediction from b's history, weights w (kernel "
                         "'scales'); the bit mask of the lanes it solved the scalar course's way, each with its "
                         "solution, residual and loops' signs (kernel 'blocks') written to b; NULL with a closed "
                         "form, without SIMD in the build, over 16 coordinates or without an exact vector form of "
                         "the residual")

#: Fields of ``sg_mechanism``, the descriptor every generated file fills (C type, name, meaning); the sizes'
#: names are the manifest's "sizes" keys, the kernels' are :data:`KERNELS` kinds.
DESCRIPTOR = (
    ("const char *", "name", "the mechanism's name"),
    ("int", "nq", "coordinates: link angles (rad) and slider travels (m)"),
    ("int", "nx", "inputs: x[0] = shaft angle, then held inputs"),
    ("int", "np", "parameters (SI)"),
    ("int", "nc", "constants hoisted out of the parameters"),
    ("int", "nobs", "observables per position (points, bodies), see the manifest"),
    ("int", "nbranch", "closed-form dyads, each with an assembly sign"),
    ("int", "nf", "force unknowns: reactions and driving torques"),
    ("int", "nfo", "force outputs per position: nf, then torques, powers, frame on parts, energies (manifest)"),
    ("int", "nload", "load slots per position: fx, fy per point of a moving body, torque per moving body"),
    ("int", "nblock", "diagonal blocks of dPhi/dq (closing loops), each with an orientation sign"),
    ("const unsigned char *", "coord_is_angle", "1 for an angle coordinate, 0 for a travel"),
    ("int", "ngroup", "groups of observables (kernel 'observe'): each point, each moving body, each cam's arc"),
    ("const int *", "group_start", "ngroup + 1 entries: group g is obs[group_start[g]] to obs[group_start[g+1]-1]"),
    ("const unsigned char *", "group_always", "1 for a group that may be non-finite where the coordinates, rates "
                                              "and constants are finite: a selective sweep computes it always"),
    ("const unsigned char *", "group_angles", "ngroup + 1 entries: 1 for a group that reads an angle coordinate's "
                                              "value (not only its cos, sin), then 1 where the rates do: a "
                                              "selective SIMD sweep computes the angles (atan2) only where they "
                                              "are read"),
) + tuple((f"sg_{kind}_fn", kind, meaning) for kind, (_, _, meaning) in KERNELS.items()) + tuple(
    (f"sg_{kind}_fn", kind, meaning) for kind, (_, _, meaning) in HOOKS.items())

#: The runtime's exported functions (csrc/sg_runtime.c): name -> (return type, arguments, meaning).
EXPORTS = {
    "sg_lu_factor": ("int", (("int", "n"), ("double *", "a"), ("int *", "piv"), ("double *", "det_sign")),
                     "LU with partial pivoting in place (row-major n x n); SG_SINGULAR below the pivot tolerance"),
    "sg_lu_solve": ("void", (("int", "n"), ("const double *", "lu"), ("const int *", "piv"), ("double *", "b")),
                    "solve with a factor of sg_lu_factor, b overwritten"),
    "sg_factor_eq": ("int", (("int", "n"), ("double *", "a"), ("int *", "piv"), ("const double *", "rs"),
                             ("double *", "cs"), ("double *", "cond")),
                     "the rates' equilibrated factor of the motion kernels in place (row-major n x n, rows scaled "
                     "by rs; n = 2: the inverse in closed form), cs (2 n: the column factors, then the columns' "
                     "largest entries), the condition number of the equilibrated matrix (n = 2: exact; else an "
                     "upper bound); SG_SINGULAR below the pivot tolerance"),
    "sg_solve_eq": ("void", (("int", "n"), ("const double *", "lu"), ("const int *", "piv"), ("const double *", "rs"),
                             ("const double *", "cs"), ("double *", "b")),
                    "solve with a factor of sg_factor_eq, b overwritten"),
    "sg_solve_lean": ("size_t", (("const sg_mechanism *", "m"), ("const sg_request *", "r")),
                      "solve()'s and kinetostatics()' lean path in one call: phi copied into blk, then the speed, "
                      "zero acceleration, err, q, qd, qdd, obs and (gv not NULL) frc without loads (n rows each; "
                      "status NULL: the statuses after them), the sweep and sg_make_continuous; SIZE_MAX and "
                      "nothing done where order is NULL and phi not ascending. Reads n, phi, speed, held, p, "
                      "branch, q_guess, opt, order, gv, nqa, qcols, noa, ocols, blk, status"),
    "sg_sweep": ("size_t", (("const sg_mechanism *", "m"), ("const sg_request *", "r")),
                 "a mechanism over n shaft angles in one call: positions, velocities, accelerations, observables "
                 "and, where gv is given, every force output (loads may be NULL); solved in the order 'order' "
                 "(a permutation of 0..n-1 that sorts phi; NULL: as given), written in the caller's order; err "
                 "(n, or NULL) the estimated relative error of the rates; returns the number of positions whose "
                 "status is not SG_OK"),
    "sg_sweep_designs": ("size_t", (("const sg_mechanism *", "m"), ("const sg_request *", "r")),
                         "nd designs over the same n shaft angles, each its own sg_sweep (its own continuation, "
                         "held inputs nd x (nx-1), parameters nd x np, branch signs nd x nbranch). Flat columns "
                         "of a position: q, qd, qdd (nq each), obs (nobs); angle_cols are made continuous as "
                         "sewgen.engine.mechanism.continuous_angles does; sel and red as sg_request says. Every "
                         "loop computes only the groups of observables sel and red read (kernels 'rates', "
                         "'observe'; the same values and statuses as the joint kernel's). Returns the number of "
                         "failed designs"),
    "sg_simd_width": ("int", (("const sg_mechanism *", "m"),),
                      "positions per block of m's SIMD sweeps (kinematics, kinetostatics; a Newton sweep's finish) "
                      "on this CPU: SG_LANES where m has a SIMD loop (the module built with SIMD, the kernels with a "
                      "vector form) and the CPU has the build's level (8: AVX-512 F, VL, DQ; 4: AVX2 and FMA), "
                      "else 1 (the scalar loop); m NULL: what this module and CPU offer any mechanism"),
    "sg_sorted": ("int", (("size_t", "n"), ("const double *", "phi")),
                  "1 where every phi[i] >= phi[i-1] (a NaN breaks it), else 0: whether a sweep of these shaft "
                  "angles needs a solving order"),
    "sg_shaft": ("int", (("size_t", "n"), ("const double *", "phi"), ("const double *", "omega"),
                         ("const double *", "alpha"), ("const double *", "src"), ("int", "nf"),
                         ("const size_t *", "f_off"), ("const size_t *", "f_step"), ("const double *", "f_sign"),
                         ("const double *", "f_arm"), ("int", "nt"), ("const size_t *", "t_off"),
                         ("const size_t *", "t_step"), ("const double *", "belt"), ("double", "belt_arm"),
                         ("int", "ncore"), ("const double *", "core"), ("const double *", "gravity"),
                         ("double", "inertia"), ("double", "span"), ("double", "mu_r"), ("double *", "out")),
                 "the upper shaft by d'Alembert at n positions: the bearings' forces on the shaft (front, rear: n x "
                 "2 each), the driving torque and the bearings' friction torque (n each) and the core masses' "
                 "position, velocity, acceleration (ncore x 3 x n x 2) into out, from the forces on the core "
                 "(x at src[f_off[2j] + i f_step[j]], y at src[f_off[2j+1] + i f_step[j]], times f_sign[j], at "
                 "arm f_arm[j]), the belt, the core masses (ncore x (mass, radius, cos and sin of the angle, "
                 "arm)) and the groups' shaft torques (src[t_off[k] + i t_step[k]]); 1 where front, rear and "
                 "torque are finite, else 0"),
    "sg_place_loads": ("void", (("size_t", "n"), ("const double *", "phi"), ("int", "nload"), ("int", "nl"),
                                ("const double *", "win"), ("const int *", "ncol"), ("const int *", "col"),
                                ("const double *", "val"), ("double *", "out"), ("unsigned char *", "mask")),
                       "sewgen.engine.loads.place_loads in C, to the bit: the (n x nload) load slots of nl loads (each "
                       "ncol[l] slots col, val; on where win[2l] (its window's start) is NaN or (phi - start) mod "
                       "2 pi <= win[2l+1]) and their (nl x n) on-masks"),
    "sg_make_continuous": ("void", (("size_t", "n"), ("int", "nq"), ("int", "nobs"), ("double *", "q"),
                                    ("double *", "obs"), ("int", "nqa"), ("const int *", "qcols"), ("int", "noa"),
                                    ("const int *", "ocols"), ("const size_t *", "order")),
                           "sewgen.engine.mechanism.continuous_angles in C, to the bit: the angle columns qcols of q "
                           "(n x nq) and ocols of obs (n x nobs) without 2 pi jumps along the order (NULL: as "
                           "given), the first position in (-pi, pi]"),
}


def c_args(args) -> str:
    """``(const double *p, double *c)``-style C parameter list of an argument tuple."""
    return ", ".join(f"{t}{'' if t.endswith('*') else ' '}{n}" for t, n in args) or "void"


def kernel_signature(kind: str, function: str) -> str:
    """The C signature of kernel ``kind`` named ``function`` (no semicolon)."""
    ret, args, _ = KERNELS[kind]
    return f"{ret} {function}({c_args(args)})"


def kernel_hook(kind: str, function: str) -> dict:
    """What a generated file needs to instantiate the inlined loop ``kind`` of :data:`HOOKS` as ``function``:
    its C signature and the argument names to pass on."""
    ret, args, _ = HOOKS[kind]
    return {"signature": f"{ret} {function}({c_args(args)})", "args": ", ".join(n for _, n in args[1:])}
