/*
 * gac.h -- the hybrid (flight + impact) simulation of an open chain of rigid links confined in a box,
 * for any model described by a const gac_model (sizes, contact tables, kernels).  Plain C99.
 *
 * The library holds everything that does not depend on the scene: the small LDL^T solves in contact space, the impact law of
 * Eq. 44-48 with complementarity (and its LCP), the constrained dynamics of resting contacts, the
 * integrators RK4, DOPRI5 and DOP853 with dense output, event location, resting contact and
 * the floor on the base chart's measure.  A model (NAME.c, written by the generator, or written by hand)
 * supplies the kernels and tables through a gac_model.
 *
 *   const gac_model *m = &NAME_model;                     (or a model filled by hand)
 *   double dwork[...gac_sim_ndouble(m)], rdwork[...gac_record_ndouble(m)];
 *   int iwork[...gac_sim_nint(m)], riwork[...gac_record_nint(m)];
 *   gac_sim sim; gac_impact_record rec; gac_options opt;
 *   gac_default_options(&opt);                            edit opt.method, opt.rtol, ...
 *   gac_sim_init(&sim, m, dwork, iwork, 0.0, q0, qd0, p, &opt);
 *   gac_record_bind(&rec, m, rdwork, riwork);
 *   while ((code = gac_sim_advance(&sim, t_end, t_eval, n_eval, &i_eval, x_eval, &rec)) == GAC_SIM_IMPACT
 *          || code == GAC_SIM_CONTACT)
 *       ... rec holds the impact just applied, or (GAC_SIM_CONTACT) a change of the resting contacts ...
 *   code is GAC_SIM_END (sim.t == t_end) or an error (< 0, see gac_error_message).
 *
 * Memory.  The model is const and shared; the caller owns every state struct and every array; the library
 * has no globals (only static const tables) and never allocates.  One gac_sim per thread.  The arrays of
 * gac_sim and gac_impact_record are pointers into the caller's dwork / iwork arrays (layouts below); after a
 * struct is copied or moved, bind it again to its own arrays (gac_sim_bind, gac_record_bind).
 *
 * Conventions.  SI units (m, kg, s, rad, N, J).  q: the model's generalised coordinates (nq), qd: their
 * time derivatives, x = [q, qd] (nx = 2 nq) the ODE state, p: the parameter vector (nparam), u: the inputs
 * (nu), each the generalised force of one actuated coordinate (N m on an angle, N on a translation).  Matrices are
 * row-major: element (i, j) of an R x C matrix is at [i*C + j].  A contact is a (point, wall) pair with a
 * gap >= 0 inside the box; its normal points into the box, and an impulse or force along it pushes the
 * point away from the wall.
 */
#ifndef GAC_H
#define GAC_H

#if defined(__cplusplus)
#  define GAC_RESTRICT
#else
#  define GAC_RESTRICT restrict
#endif

/* ---- return codes ------------------------------------------------------------------------------ */
#define GAC_OK                     0
#define GAC_ERR_BAD_CONTACT       -1   /* contact set empty, too long, repeated or out of range */
#define GAC_ERR_SINGULAR_MASS     -2   /* I_f singular to double precision: its solve (inertia_solve) is not
                                          finite (mass, length and inertia ratios beyond 15 digits) */
#define GAC_ERR_SINGULAR_IMPACT   -3   /* rows of the contact set linearly dependent */
#define GAC_ERR_LCP               -4   /* complementarity impact has no solution / too many contacts */
#define GAC_ERR_GIMBAL_LOCK       -5   /* theta_0 too close to the gimbal lock of the base chart: the base
                                          chart's measure chi = |det E| (|cos theta_0| for the default twists)
                                          is below GAC_CHART_FLOOR, where I_f's solves lose 1e-6 (16 eps / chi^2);
                                          the hybrid loop continues on the model's second chart (chart_b) below
                                          sqrt(16 eps / rtol), or, without one, stops there with this code */
#define GAC_ERR_BAD_OPTION       -10   /* an option or argument is out of range (the ranges: gac_error_message) */
#define GAC_ERR_MAX_STEPS        -11   /* opt.max_steps reached in one advance call */
#define GAC_ERR_STEP_SIZE        -12   /* adaptive step size fell below round-off */
#define GAC_ERR_NONFINITE        -13   /* the state became NaN or infinite */
#define GAC_ERR_TOO_MANY_CONTACTS -14  /* more approaching contacts at once than nq */
#define GAC_ERR_SINGULAR_CONTACT -15   /* the resting contact constraints are dependent */
#define GAC_ERR_IMPACT_ACCURACY  -16   /* an impact failed its post-conditions (F >= 0, no approach, no energy
                                          gain, e = 1 energy kept) beyond round-off, or its round-off bound
                                          (record.roundoff) exceeds GAC_IMPACT_ROUNDOFF_MAX, or its
                                          elastic rounds (every contact e = 1) did not end: ill-conditioned */
#define GAC_ERR_UNSTABLE         -17   /* RK4: 3 steps in a row at h rho > 2.5 (or one > 10), rho the rate of the
                                          chain's fastest mode between the last two stages: dt is past RK4's
                                          stability (about 2.8 / rho); the state is the last step's */
#define GAC_ERR_LOST_CONTACT     -18   /* at an impact a point lay beyond its wall by more than contact_tol
                                          plus the simultaneity window: a crossing was missed because the
                                          motion is too fast or I_f too ill-conditioned for the tolerance */
#define GAC_ERR_START_OUTSIDE    -19   /* gac_sim_init: a contact point starts beyond its wall, deeper than the
                                          loop's own lost-contact depth (contact_tol + the simultaneity window) */
#define GAC_ERR_NULL_ARGUMENT    -20   /* a pointer argument that must not be NULL is NULL (see each function) */
#define GAC_ERR_BAD_MODEL        -21   /* the model descriptor is inconsistent (gac_model_check) */
#define GAC_ERR_BAD_INPUT        -22   /* an input u (set by gac_sim_set_input, or written by the controller)
                                          is NaN or infinite */
#define GAC_ERR_FRICTION         -23   /* the resting contacts with Coulomb friction have no unique, bounded normal
                                          forces (their system is no P-matrix: the Painleve paradox), and the
                                          tangential impact the loop takes there has no solution either (or the
                                          state after it is again no P-matrix); see "Tangential impact" below */
#define GAC_ERR_BAD_PARAMETER    -24   /* a parameter is outside its allowed range or breaks a relation with others
                                          (gac_check_parameters gives its index; the model's parameter_info its
                                          name and what it allows) */
#define GAC_ERR_IMPACT_FRICTION  -30   /* the frictional impact law's solve did not bring its conditions below
                                          GAC_FRICTION_RESIDUAL_MAX (record.residual says how far it got) */
#define GAC_ERR_IMPACT_ENERGY    -31   /* an impact gained kinetic energy: the Newton + Coulomb law
                                          (opt.impact_law), whose slip reversal during the impact can (Kane's
                                          rod); the default law cannot */
#define GAC_ERR_LINK_CONTACT     -32   /* a contact of two links (GAC_CONTACT_LINK) or of a link on an obstacle
                                          met what the loop does not do with it: a geometry without a derivative
                                          where one is needed (crossing axes, a link lying parallel to a face or to
                                          the other link while not held) */
#define GAC_ERR_LINK_REST        -33   /* two links would come to rest on each other (or a link on a fixed
                                          obstacle, GAC_CONTACT_OBSTACLE) where that contact cannot be held: its
                                          normal has no derivative (crossing axes); struck opt.zeno_impacts
                                          times in a row at shrinking intervals (e < 1: the Zeno rule that lands
                                          a wall's contact) or at one instant
                                          (within 1e-12 (1 + |t|) s).  Also a held one whose normal loses its
                                          derivative */
#define GAC_ERR_LINK_LINE        -34   /* a link held on another link (or a bar, or a box's face) turned parallel to it: its
                                          other end came closer than the held point by more than round-off (1e-12
                                          of the two lengths): a line contact, which the pair's one-point contact
                                          cannot hold; the run stops at the start of that step, before the other
                                          end passes through */
#define GAC_ERR_PAINLEVE_STALL   -35   /* the steps of one stretch between events (or resolutions of the
                                          paradox) met GAC_PAINLEVE_STALL states where the resting contacts'
                                          forces do not exist (the Painleve paradox: a trial stage or the dense
                                          output beyond a boundary where the normal force grows without bound)
                                          without ever shrinking onto that boundary, where the tangential impact
                                          is taken: the motion follows it with unbounded forces, at steps of its
                                          scale */

/* ---- how gac_sim_advance ends: the run's budgets (< 0) and status (> 0) ------------------------ */
#define GAC_ERR_WALL_TIME        -25   /* the run used opt.max_wall_time seconds of its clock (gac_sim_set_clock)
                                          since gac_sim_init or the last gac_sim_set_clock */
#define GAC_ERR_STOPPED          -26   /* the progress callback (gac_sim_set_progress) asked the run to stop */
#define GAC_ERR_MAX_IMPACTS      -27   /* opt.max_impacts impacts applied since gac_sim_init: the run stops before
                                          the next step (raise it to go on, then gac_sim_advance again) */
#define GAC_ERR_DRIFT            -28   /* the energy balance of the run (sim.energy_residual) left more than
                                          opt.energy_tol of the run's energy scale (sim.energy_scale): the
                                          integration error is beyond the tolerance (tighten rtol) */
#define GAC_ERR_PROJECTION       -29   /* bringing the state back onto the resting contacts after a step changed
                                          the energy by more than opt.energy_tol of the energy scale: the step left
                                          the constraints too far (tighten rtol) */
#define GAC_SIM_END      1    /* reached t_end */
#define GAC_SIM_IMPACT   2    /* ended at an impact, already applied; see the record (which may also list
                                 contacts come to rest, released, stuck or set slipping by the impact) */
#define GAC_SIM_CONTACT  3    /* ended where the resting set changed without an impact: a contact
                                 released (its force reached 0), the contacts gac_sim_init puts at rest, or a
                                 resting point on a rough wall that came to stick or began to slip; record.t,
                                 landed[], released[], stuck[], slipped[] are filled, ncontact = 0 */

/* ---- integrators (gac_options.method) -------------------------------------------------------- */
#define GAC_METHOD_RK4     0   /* classical fixed-step RK4 (opt.dt), cubic Hermite dense output */
/* The smallest relative tolerance the adaptive methods accept: about 50 unit round-offs, below which a
 * step's error estimate is round-off and the step size collapses ("step size underflow"). */
#define GAC_RTOL_MIN 1e-14

#define GAC_METHOD_DOPRI5  1   /* Dormand-Prince 5(4), adaptive (opt.rtol, opt.atol), 4th-order dense output */
#define GAC_METHOD_DOP853  2   /* Dormand-Prince 8(5,3), adaptive, 7th-order dense output */

/* ---- impact laws at walls with Coulomb friction (gac_options.impact_law, gac_impact_record.law) ---- */
#define GAC_IMPACT_LAW_FRICTIONLESS   0   /* Newton's law with complementarity (Eq. 47), the walls' friction acting
                                             only on resting contacts; a record's law when no contact with
                                             friction took part */
#define GAC_IMPACT_LAW_GDI            1   /* the default: Coulomb's cone on gamma+ + e gamma- (normal and tangential
                                             velocities, one restitution e per contact): never gains energy
                                             (gac_impact_friction) */
#define GAC_IMPACT_LAW_NEWTON_COULOMB 2   /* Newton's restitution on the normal velocity, Coulomb's cone on the
                                             tangential velocity after the impact: can gain energy (Kane's rod);
                                             for comparison */
#define GAC_IMPACT_LAW_GDI_COMMON_E   3   /* a record's law only: GDI, a round solved with the smallest e of its
                                             contacts for all of them (its own e's would have gained energy) */
#define GAC_IMPACT_LAW_GDI_TANGENTIAL 4   /* a record's law only: a tangential impact (impact without collision) at
                                             resting contacts whose sliding system is no P-matrix (the Painleve
                                             paradox, the dynamic jam): GDI with e = 0 and normal velocities 0
                                             before, its non-trivial solution (see "Tangential impact" below) */

/* ---- limits ----------------------------------------------------------------------------------- */
#define GAC_CHART_FLOOR  5.96e-5   /* sqrt(16 eps / 1e-6): gac_impact refuses a base chart measure below it */
#define GAC_LCP_CAP      16        /* contacts one complementarity solve takes at most: min(nq, 16) */
#define GAC_LINK_NGEOMETRY 6     /* doubles of a link contact's geometry: gap, s, t, n (gac_link_gap) */
#define GAC_MAX_ROUNDS   256       /* rounds of the impact law before its plastic closing round */
#define GAC_IMPACT_ROUNDOFF_MAX 1e-2  /* an impact whose round-off bound (record.roundoff) exceeds this stops the
                                         run (GAC_ERR_IMPACT_ACCURACY): its energy is not known */
#define GAC_FRICTION_RESIDUAL_MAX 1e-9  /* the frictional impact law's conditions, relative: beyond it, or beyond
                                         16 eps cond(W) of a round's contact-space W (its LDL^T pivots' spread)
                                         where that is larger, the impact is refused (GAC_ERR_IMPACT_FRICTION); the
                                         residual left counts in the impact's accuracy (record.roundoff) */
/* What an impact's measured accuracy (record.roundoff) is made of: its largest part (record.roundoff_cause) */
#define GAC_ROUNDOFF_FLOOR          0   /* none above the 1e-10 every record states at least */
#define GAC_ROUNDOFF_STORED         1   /* the stored velocities' energy miss: the first-order change of T to the
                                           velocities that balance the impulses exactly and meet the law's targets
                                           (rounding the velocities to doubles, along a soft direction of I_f) */
#define GAC_ROUNDOFF_EVALUATION     2   /* what evaluating the momentum balance resolves (its measured floor) */
#define GAC_ROUNDOFF_LAW            3   /* the contact law's residual: its conditions solved in one round (the
                                           frictional law's cone and complementarity), or the velocities' miss of
                                           the rounds' own after several, and the rest rule's work */
#define GAC_ROUNDOFF_IDENTITY       4   /* the energy identity's residual that the momentum balance does not explain
                                           (evaluating T) */
#define GAC_ROUNDOFF_ROUNDS_ENERGY  5   /* after several rounds, T's change beyond what the law gives */
#define GAC_ROUNDOFF_HOLD           6   /* holding the resting contacts after the law */
#define GAC_ROUNDOFF_LINK           7   /* the balance of a law with link pairs or obstacles */
/* Which of an impact's checks refused it (record.refusal, with GAC_ERR_IMPACT_ACCURACY) */
#define GAC_REFUSED_NONE        0
#define GAC_REFUSED_ACCURACY    1   /* its measured accuracy above GAC_IMPACT_ROUNDOFF_MAX: its energy not known */
#define GAC_REFUSED_ELASTIC_ROUNDS 2   /* elastic rounds (every contact e = 1) that did not end */
#define GAC_REFUSED_ELASTIC_CHANGE 3   /* an elastic law that changed the kinetic energy beyond its accuracy */
#define GAC_REFUSED_PULL        4   /* an impulse < 0 beyond round-off */
#define GAC_REFUSED_GAIN        5   /* the kinetic energy grew beyond the accuracy */
#define GAC_REFUSED_APPROACH    6   /* a contact left approaching its wall faster than the accuracy allows */
#define GAC_SLOW_SLIDING 4         /* a resting point sliding slower than this many friction_velocity is in (or
                                      near) the regularised friction's stiff, viscous regime: sim.n_slow_sliding */

#ifdef __cplusplus
extern "C" {
#endif

/* ---- the model -------------------------------------------------------------------------------- */

/* Kernels: pure functions of their inputs, outputs not aliasing inputs.
 *   q (nq), qd (nq), u (nu; may be NULL when nu = 0), p (nparam) in; out as documented per kernel in gac_model. */
typedef void (*gac_kernel_q)(const double *q, const double *p, double *out);
typedef void (*gac_kernel_qqd)(const double *q, const double *qd, const double *p, double *out);
typedef void (*gac_kernel_qqdu)(const double *q, const double *qd, const double *u, const double *p, double *out);
typedef void (*gac_kernel_rhs)(double t, const double *x, const double *u, const double *p, double *xdot);
/* q, a vector v (its size and meaning per kernel), p -> out: the linear operators of the model */
typedef void (*gac_kernel_qv)(const double *q, const double *v, const double *p, double *out);
#define GAC_TANGENT_BLOCK 4    /* directions of a model's forward_dynamics_tangent_block */
/* q, qd, u, p and a direction (dq, dqd, du, dp) -> the directional derivative of a qqdu kernel's output */
typedef void (*gac_kernel_tangent)(const double *q, const double *qd, const double *u, const double *p,
                                   const double *dq, const double *dqd, const double *du, const double *dp,
                                   double *out);

/* q, a vector v (its size per kernel), p and a direction (dq, dv, dp) -> the directional derivative of a qv kernel */
typedef void (*gac_kernel_qv_tangent)(const double *q, const double *v, const double *p, const double *dq,
                                      const double *dv, const double *dp, double *out);
/* q, p and a direction (dq, dp) -> the directional derivative of a q kernel */
typedef void (*gac_kernel_q_tangent)(const double *q, const double *p, const double *dq, const double *dp,
                                     double *out);
/* q, a vector v (qd or f), p -> out in long double: a kernel's long-double variant (its own flattened program, every
 * intermediate a long double, the inputs double) */
typedef void (*gac_kernel_qv_ld)(const double *q, const double *v, const double *p, long double *out);

/* A controller: writes the inputs u (nu) for time t (s) and state (q, qd).  On entry u holds the inputs
 * last given to gac_sim_set_input.  Called at every stage of the integrators and wherever the loop needs
 * the flight dynamics (events, impacts, resting contact), so it must be a function of (t, q, qd) and of what
 * user points to, not of how often it is called.  user: the caller's pointer, passed through. */
typedef void (*gac_controller)(double t, const double *q, const double *qd, double *u, void *user);

/* A controller's Jacobian (gac_sim_set_controller_jacobian), for the sensitivities through its state feedback: writes
 * du_dq[i*nq + k] = d u_i / d q_k and du_dqd[i*nq + k] = d u_i / d qd_k (each nu x nq, row-major; u in its units, N m
 * or N, per rad or m, and per rad/s or m/s) at time t (s) and state (q, qd), in the coordinates the controller sees
 * (the model's, chart A's).  user: the controller's pointer. */
typedef void (*gac_controller_jacobian)(double t, const double *q, const double *qd, double *du_dq, double *du_dqd,
                                        void *user);

/* A clock for the wall-time budget: seconds from any fixed origin, never decreasing.  user: passed through.
 * The default (NULL) is C's clock(): the processor time of the process, which on a target without a clock
 * counts nothing; give a monotonic wall clock where the host has one. */
typedef double (*gac_clock)(void *user);

/* Progress of a run: called with the simulated time t (s), the steps (accepted and rejected) and the impacts since
 * gac_sim_init, every GAC_LOOK_STEPS steps and at the start of every gac_sim_advance; returning nonzero stops the
 * run (GAC_ERR_STOPPED) at that step end, from which a later gac_sim_advance may go on.  user: passed through. */
typedef int (*gac_progress)(double t, long n_steps, long n_impacts, void *user);
#define GAC_LOOK_STEPS 64      /* steps between two looks at the clock and the progress callback */
#define GAC_PAINLEVE_STALL 1000 /* rejections at the Painleve paradox in one stretch that stop the run */

/* One contact: a point of the chain and a wall (kind GAC_CONTACT_WALL), or a joint and its stop (kind
 * GAC_CONTACT_STOP: a unilateral constraint on the coordinate q[coordinate], gap = normal_sign (q - limit) in
 * rad, its Jacobian row a row of the identity).  Both are handled alike: events, impacts, resting.
 * Or two links as capsules (kind GAC_CONTACT_LINK: links point and coordinate, 1-based, gap = their segments'
 * distance less its m->link_radius entry, gac_link_gap, or with end != GAC_END_LINK the distance of link point's
 * joint point O_point or O_point+1 from link coordinate's segment, a pair's end contact; its direction J^T n from
 * the closest points, gac_link_direction; no Jacobian
 * row).  Link contacts come last in the table, after every contact of the contact_gaps kernel; they take part in
 * events and impacts (with Coulomb friction along their contact frame where rough) and in the resting set, held by
 * their direction g and its bias dg(qd) . qd (not where g has no derivative), rough ones stuck or sliding along the
 * frame's tangents as a rough wall's point (see "Sticking").
 * Or a link and a fixed obstacle (kind GAC_CONTACT_OBSTACLE: link point, 1-based, and obstacle coordinate,
 * 0-based into m->obstacle_shapes; gap = the distance of the link's segment (or, for a plane, of one of its joint
 * points: field end) from the obstacle, less its m->link_radius entry (the link's radius) and the obstacle's
 * radius, gac_contact_geometry, the obstacle's geometry read from p, gac_obstacle_shape): handled as a link pair
 * whose second side never moves.  Obstacle contacts come after the link pairs. */
#define GAC_CONTACT_WALL 0
#define GAC_CONTACT_STOP 1
#define GAC_CONTACT_LINK 2
#define GAC_CONTACT_OBSTACLE 3

/* The kinds of a fixed obstacle (gac_model.obstacle_shapes): the capsule about a segment (a bar), an oriented box,
 * a half-space bounded by a plane, a sphere (the capsule about a point); each shape GAC_OBSTACLE_NSHAPE doubles.
 * The geometry's runtime parameters (gac_model.obstacle_params), in this order from the obstacle's first: a bar's
 * ends a, b (m) and radius (7), a box's centre, half extents (m) and rotation (row-major) (15), a plane's point (m)
 * and unit normal (6), a sphere's centre (m) and radius (4). */
#define GAC_OBSTACLE_SEGMENT 0
#define GAC_OBSTACLE_BOX 1
#define GAC_OBSTACLE_PLANE 2
#define GAC_OBSTACLE_SPHERE 3
#define GAC_OBSTACLE_NSHAPE 16
typedef struct {
    int point;            /* wall: the point O_point, 1-based (1..npoint); its coordinates are
                             contact_points[3*(point-1) .. 3*(point-1)+2].  stop: the joint k (information).
                             link, obstacle: the (first) link i (1..npoint-1) */
    int axis;             /* wall: its normal axis, 0..2 for X1..X3.  stop: -1 */
    int normal_sign;      /* wall: +1: the inward normal is +X_axis (a *_min wall), -1: -X_axis (a *_max wall).
                             stop: +1 for a lower limit, -1 for an upper one */
    int row;              /* the row of contact_jacobian / contact_bias for (point, axis), 0..njrow-1 */
    int e_index;          /* restitution e of the wall or stop (Newton's law, Eq. 47): p[e_index], or e_value
                             when e_index < 0 (a constant of the model) */
    double e_value;
    int kind;             /* GAC_CONTACT_WALL (0), GAC_CONTACT_STOP (1), GAC_CONTACT_LINK (2) or
                             GAC_CONTACT_OBSTACLE (3) */
    int coordinate;       /* stop: the index into q of its joint's angle (0..nq-1); link: the second link j
                             (> point + 1; an end contact: any link two or more from point); obstacle: the obstacle
                             (0..nobstacle-1); wall: unused */
    int has_friction;     /* wall, link, obstacle: 1 if it has Coulomb friction (0: frictionless; a zero-initialised
                             entry), at impacts and at rest; a link pair's and an obstacle's along its contact frame */
    int friction_index;         /* its friction coefficient c_f: p[friction_index], or friction_value when < 0 */
    double friction_value;
    int trow[2];          /* the Jacobian rows of the point along the wall's two tangential axes (ascending), -1 for
                             an axis the model does not move along (the normal of a planar model) */
    int end;              /* link, obstacle: the part of link point its gap is measured from: GAC_END_LINK (0, the
                             whole segment O_i O_i+1), GAC_END_START (1, the joint point O_i alone) or
                             GAC_END_FINISH (2, O_i+1 alone: a plane's, a box's and a bar's joint points, a link
                             pair's ends against the other link); walls, stops: 0.  A link's or a pair's contact
                             beside such contacts gives way to them where they measure the same (gac_internal.h,
                             gac_redundant_depth) */
} gac_contact;
#define GAC_END_LINK 0
#define GAC_END_START 1
#define GAC_END_FINISH 2

/* The base chart's measure chi(q) = |a . (e_z x Rz(theta_0) b)| (|det E|; |cos theta_0| for the default
 * twists): a = T_0^T e_z, b = T_1 e_z, only their first two components enter.  chi = 0 is the gimbal lock. */
typedef struct {
    double a[2], b[2];
    int theta0_index;     /* theta_0 = q[theta0_index], or theta0_value when theta0_index < 0 */
    double theta0_value;  /* rad */
} gac_chart;

/* What one parameter may be (a row of gac_model.parameter_info): finite, lo <= p[i] <= hi, and 0 or at least the
 * smallest normal double (DBL_MIN) in magnitude; lo = hi for a value the model has built in.  range says it in
 * words, with the relation the model's check names this parameter by if there is one
 * ("must be within [-1e+09, 1e+09] m, and > wall_x1_min"). */
typedef struct {
    const char *name;     /* as in the parameter layout: "g", "l_3", "e_x2_min", "upper_2" */
    double lo, hi;
    const char *range;
} gac_parameter_info;

/* A model's check of a parameter vector p (nparam): GAC_OK, or GAC_ERR_BAD_PARAMETER with *bad_index (if bad_index
 * is not NULL) the first parameter outside its range (parameter_info) or, when every range holds, the parameter a
 * failed relation is named by (a wall's max not above its min, a joint's upper limit not above its lower one,
 * a rigid link's inertia not physical: Ixx of that link). */
typedef int (*gac_parameter_check)(const double *p, int *bad_index);

/* The base orientation's parametrisation (docs/model.md, "Frame convention"):
 *     ^{ref}R_1 = T_-1 Rz(theta_-1) T_0 Rz(theta_0) T_1 Rz(theta_1),   omega_1 = E(theta) thetadot,
 * E's columns the three base joint axes in the reference frame.  T_0 and T_1 turn each axis a right angle from
 * the previous one (T_0[2][2] = T_1[2][2] = 0), so |det E| = |u_-1 x z_1|: the chart is singular when link 1's
 * joint axis z_1 lies along the fixed first axis u_-1 = T_-1 e_z.  Matrices row-major. */
typedef struct {
    double T_m1[9], T_0[9], T_1[9];
    int index[3];         /* theta_-1, theta_0, theta_1 = q[index[0..2]]; -1 when the model holds one fixed */
} gac_base;

typedef struct gac_model gac_model;

struct gac_model {
    const char *name;     /* the model's name (NAME) */
    int n;                /* real links (information only) */
    int nq;               /* generalised coordinates, >= 1 */
    int nx;               /* ODE state size, 2 nq */
    int nparam;           /* parameters */
    int nu;               /* inputs: generalised forces of the actuated coordinates, >= 0 */
    int npoint;           /* contact points O_1..O_npoint (contact_points gives 3 npoint numbers) */
    int ncontact;         /* contacts (rows of contacts[]), >= 0 */
    int njrow;            /* rows of contact_jacobian and contact_bias */
    const gac_contact *contacts;       /* [ncontact] */
    gac_chart chart;
    const double *default_parameters;  /* [nparam] */
    const double *q0, *qd0;            /* [nq] each: the scene's initial state */
    /* kernels: every one costs O(n) for a chain of n links; the library never forms I_f or the contact
       Jacobian J (njrow x nq), it applies them (gac_mass_matrix and friends below form them when asked) */
    gac_kernel_qqdu forward_dynamics;  /* q, qd, u, p -> qdd (nq) solving I_f qdd = R in flight (Eq. 12), R with
                                          the generalised forces of inputs, joint springs and dampers */
    gac_kernel_qv  inertia_solve;      /* q, Q (nq), p -> I_f^-1 Q (nq): the response to generalised forces Q */
    gac_kernel_qqd generalized_momentum; /* q, qd, p -> I_f qd (nq) = dT/dqd */
    gac_kernel_q   contact_points;     /* q, p -> O_1..O_npoint (npoint x 3, m) */
    gac_kernel_qqd contact_velocities; /* q, qd, p -> their velocities (npoint x 3, m/s) (Eq. 42); linear in qd:
                                          J w is read off contact_velocities(q, w) */
    gac_kernel_qv  contact_generalized_force; /* q, f (njrow), p -> J^T f (nq): the generalised force of a force
                                          f[r] along each Jacobian row r (N on a point's axis, N m on a stop) */
    gac_kernel_q   contact_gaps;       /* q, p -> gap of each contact (ncontact, m; >= 0 inside) */
    gac_kernel_qqd contact_bias;       /* q, qd, p -> Jdot qd (njrow, m/s^2): the rows' accelerations at qdd = 0 */
    gac_kernel_qqd energy;             /* q, qd, p -> E[0] kinetic, E[1] potential energy (J), joint springs
                                          included */
    gac_kernel_rhs rhs;                /* t, x, u, p -> xdot = [qd, qdd] (nx); t unused */
    gac_kernel_qqdu forward_dynamics_energy; /* q, qd, u, p -> [qdd (nq), T, V]: forward_dynamics and energy in
                                          one call (the loop's derivative at a step's end, where it also wants the
                                          energy); NULL: none (the loop calls the two) */
    gac_kernel_tangent forward_dynamics_tangent; /* q, qd, u, p, dq, dqd, du (nu), dp (nparam) -> d qdd (nq): the
                                          directional derivative of forward_dynamics (forward mode, exact, O(n));
                                          NULL: none (a rolled forward dynamics; gac_linearize refuses) */
    gac_kernel_qqdu power;             /* q, qd, u, p -> P[0] power of the inputs, P[1] dissipation of the
                                          dampers (W, >= 0); NULL: nothing in flight does work but gravity */
    double friction_velocity;          /* v_s (m/s, > 0 when a contact has friction): a resting point slides against
                                          -c_f lambda v_t / max(|v_t|, v_s), lambda its normal force, v_t its
                                          velocity along the wall (Coulomb above v_s, viscous below) */
    gac_parameter_check check_parameters;  /* the ranges of parameter_info and the relations between parameters;
                                          called by gac_sim_init (NULL: parameters need only be finite) */
    const gac_parameter_info *parameter_info; /* [nparam]: each parameter's name and allowed values (NULL: none) */
    double (*weight_scale)(const double *p); /* p -> M |g| L (J), the work to lift the whole chain by its own length:
                                          the energy balance's scale for a chain whose T + V is near 0 (at rest on
                                          the floor); NULL: none (the scale is then T + |V| alone) */
    gac_base base;                     /* this chart's base parametrisation (gac_chart.c) */
    const gac_model *chart_b;          /* the same chain on a second base chart (NULL: none): base.T_m1 replaced by
                                          C T_-1, C a constant right-angle rotation turning u_-1 perpendicular,
                                          every other entry the same (sizes, contacts, parameters); only theta_-1,
                                          theta_0, theta_1 and their rates differ.  The loop integrates on it
                                          near this chart's gimbal lock (gac_options.chart_switch) */
    gac_kernel_tangent forward_dynamics_tangent_block; /* forward_dynamics_tangent along GAC_TANGENT_BLOCK directions
                                          at once (each seed and the output GAC_TANGENT_BLOCK arrays of its size, one
                                          after the other), the primal part computed once; NULL: none (the
                                          sensitivities then call forward_dynamics_tangent per direction) */
    /* the tangents of four more kernels, for the sensitivities of impacts and resting contacts (gac_sens_attach);
       NULL: none (a rolled forward dynamics, tangent=False) */
    gac_kernel_qv_tangent inertia_solve_tangent;   /* q, Q, p, dq, dQ, dp -> d(I_f^-1 Q) (nq) */
    gac_kernel_qv_tangent contact_generalized_force_tangent; /* q, f, p, dq, df (njrow), dp -> d(J^T f) (nq) */
    gac_kernel_q_tangent contact_gaps_tangent;     /* q, p, dq, dp -> d gap (ncontact) */
    gac_kernel_qv_tangent contact_bias_tangent;    /* q, qd, p, dq, dqd, dp -> d(Jdot qd) (njrow) */
    /* the tangents of the points and their velocities, for the derivative of a link pair's or an obstacle's row
       (gac_contact_normal_tangent); NULL: none (it then differences contact_points and contact_velocities) */
    gac_kernel_q_tangent contact_points_tangent;   /* q, p, dq, dp -> d O_1..O_npoint (npoint x 3) */
    gac_kernel_qv_tangent contact_velocities_tangent; /* q, qd, p, dq, dqd, dp -> d(their velocities) (npoint x 3) */
    /* long-double variants of three kernels, for the impact's accuracy (gac_impact_accuracy evaluates its momentum
       balance and energy identity with them); NULL: none (extended=False, chart B; then in double) */
    gac_kernel_qv_ld generalized_momentum_ld;      /* q, qd, p -> I_f qd (nq) */
    gac_kernel_qv_ld contact_generalized_force_ld; /* q, f (njrow), p -> J^T f (nq) */
    gac_kernel_qv_ld energy_ld;                    /* q, qd, p -> E[0] kinetic, E[1] potential energy (J) */
    const double *link_radius;         /* r_i + r_j (m, >= 0) of each link contact (GAC_CONTACT_LINK), then the
                                          link's r_i of each obstacle contact (GAC_CONTACT_OBSTACLE; the obstacle's
                                          own radius is part of its geometry), in table order (link_radius[0]: the
                                          first after the kernel's contacts); NULL when the model has none */
    int nobstacle;                     /* fixed obstacles (>= 0) */
    const char *const *obstacle_names; /* [nobstacle]: each obstacle's name (contacts are named L<i>/<name>) */
    const double *obstacle_shapes;     /* [GAC_OBSTACLE_NSHAPE nobstacle] (nobstacle > 0): each obstacle's kind
                                          (GAC_OBSTACLE_*), then a bar's or sphere's ends a, b (box frame, m; a
                                          sphere's a = b, its centre) and radius, a box's centre, half extents (m)
                                          and rotation (row-major 3x3, columns its axes), or a plane's point (m) and
                                          unit normal (into the free side): the kind always, the geometry where
                                          obstacle_params gives none (gac_obstacle_shape) */
    const int *obstacle_params;        /* [nobstacle] or NULL: the index in p of obstacle o's first geometry
                                          parameter (the order of GAC_OBSTACLE_*), -1 where its geometry is the
                                          constants of obstacle_shapes (a model built with bake_params; NULL: every
                                          obstacle's) */
    /* several chains, several of which turn their base in 3D (docs/simulation.md, "Several chains"): each turning
       chain has its own base chart, switched on its own */
    int nbase;                         /* turning bases (>= 2); 0: the one base `base` (measure `chart`), as a
                                          one-chain model has */
    const gac_base *bases;             /* [nbase]: each turning chain's base on this model's chart (`base` is the
                                          first) */
    const gac_chart *charts;           /* [nbase]: their measures (`chart` is the first); gac_chart_measure is the
                                          smallest */
    const gac_model *const *chart_models; /* [2^nbase], on chart A's model (nbase <= GAC_CHART_BASES_MAX): the
                                          model with base j on its chart B where bit j of the index is set (index 0
                                          the model itself, the last its chart_b); NULL: none */
};

/* GAC_OK if the descriptor is consistent (sizes > 0 where needed, nx = 2 nq, tables and kernels present,
 * contact entries in range, parameter_info rows named with lo <= hi), else GAC_ERR_BAD_MODEL (m NULL:
 * GAC_ERR_NULL_ARGUMENT). */
int gac_model_check(const gac_model *m);

/* ---- parameters ------------------------------------------------------------------------------- */

/* Every parameter finite and, when the model has a check_parameters, in its range and relations: GAC_OK,
 * GAC_ERR_BAD_PARAMETER (*bad_index, if bad_index is not NULL: the parameter that fails; m->parameter_info, when
 * not NULL, names it and says what it allows) or GAC_ERR_NULL_ARGUMENT (m or p NULL).  gac_sim_init calls it. */
int gac_check_parameters(const gac_model *m, const double *p, int *bad_index);

/* 1 if value is finite, within [lo, hi], and 0 or at least DBL_MIN in magnitude; else 0.  The range test of one
 * parameter (lo, hi of its parameter_info row). */
int gac_in_range(double value, double lo, double hi);

/* 1 if I = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) (kg m^2, about the centre of mass) is a physical inertia: its principal
 * moments a <= b <= c (eigenvalues by cyclic Jacobi rotations) have a >= -tol and a + b >= c - tol,
 * tol = 1e-12 max(1, c), the scene loader's test; else 0.  The six entries must be finite. */
int gac_inertia_admissible(const double *I);

/* 1 if R (row-major 3x3, finite) is a proper rotation: |R^T R - I| <= 1e-9 entrywise and |det R - 1| <= 1e-9, the
 * scene loader's test of a box's rotation; else 0. */
int gac_rotation_admissible(const double *R);

/* 1 if n (3, finite) is a unit vector: | |n| - 1 | <= 1e-9, the scene loader's test of a plane's normal; else 0. */
int gac_unit_admissible(const double *n);

/* y = [qdd (nq), T, V] at (q, qd): m->forward_dynamics_energy, or where the model has none (its forward dynamics
 * rolled code) m->forward_dynamics and m->energy. */
void gac_forward_dynamics_energy(const gac_model *m, const double *q, const double *qd, const double *u,
                                 const double *p, double *y);

/* ---- the dense matrices, formed from the kernels' O(n) operators (O(n^2) each; for analysis) -------- */

/* I_f (nq x nq, row-major, symmetric): column j = generalized_momentum(q, e_j), symmetrised. */
void gac_mass_matrix(const gac_model *m, const double *q, const double *p, double *M);
/* R (nq) of I_f qdd = R in flight: generalized_momentum(q, forward_dynamics(q, qd, u)). */
void gac_bias(const gac_model *m, const double *q, const double *qd, const double *u, const double *p, double *R);
/* J (njrow x nq, row-major): row r = contact_generalized_force(q, e_r). */
void gac_contact_jacobian(const gac_model *m, const double *q, const double *p, double *J);

/* ---- inverse dynamics (gac_inverse.c) --------------------------------------------------------- */

/* tau (nq): the generalised forces that, added to the model's own (gravity, inputs u, joint springs and dampers),
 * give the accelerations qdd (nq) at (q, qd) in flight: tau = I_f qdd - R(q, qd, u) = I_f (qdd - qdd_free), by one
 * forward_dynamics and one generalized_momentum (O(n) each).  N for X1..X3, N m for the angles.  u may be NULL when
 * nu = 0. */
void gac_inverse_dynamics(const gac_model *m, const double *q, const double *qd, const double *qdd, const double *u,
                          const double *p, double *tau);

/* ---- linearisation (gac_linearize.c) ------------------------------------------------------------- */

/* The flight dynamics x_dot = f(x, u), x = [q, qd] (nx = 2 nq), linearised at (q, qd, u) for parameters p:
 * A = df/dx (nx x nx, row-major) and B = df/du (nx x nu, row-major), exact to round-off, by m->forward_dynamics_tangent
 * once per column (nx + nu calls, O(n) each).  A = [[0, I], [d qdd/dq, d qdd/dqd]], B = [[0], [d qdd/du]]; A's
 * columns are per rad or m (q) and per rad/s or m/s (qd), B's per N m or N.  Caller-owned A and B, not aliasing the
 * inputs; B and u may be NULL when nu = 0.  Returns GAC_OK, GAC_ERR_NULL_ARGUMENT (m, q, qd, p or A NULL, or B with
 * nu > 0) or GAC_ERR_BAD_MODEL (the model has no tangent kernel: its forward dynamics is rolled code, or it was
 * generated with tangent=False). */
int gac_linearize(const gac_model *m, const double *q, const double *qd, const double *u, const double *p, double *A,
                  double *B);

/* ---- workspace sizes ------------------------------------------------------------------------------ */
/* One formula each, as macros of the model's sizes: the functions below apply them to a descriptor, and a
 * generated NAME.h defines its storage sizes by them (NAME_SIM_NDOUBLE is GAC_SIM_NDOUBLE(NAME_NQ, ...)), so
 * that a model's arrays can be sized at compile time.  friction: 1 if some contact has has_friction, else 0. */

/* max(n, 1): the length of an array with one entry per contact or per Jacobian row, never 0. */
#define GAC_AT_LEAST_1(n) ((n) > 0 ? (n) : 1)

/* Doubles of the work array of gac_impact, gac_impact_complementarity, gac_impact_friction and
 * gac_constrained_dynamics: 2 nq^2 + nq + 3 npoint + max(njrow, 1), laid out as Y (nq*nq: row a = I_f^-1 n_a of
 * contact a of the set) | A (nq*nq: N I_f^-1 N^T, ncontact_set x ncontact_set) | g (nq) | vel (3 npoint) |
 * f (max(njrow, 1)); a model with friction needs 22 nq^2 more: Z (nq*nq) | B (nq*nq) (the responses to the
 * tangential directions, up to 2 nq of them) | W (9 nq*nq: the contact-space inverse inertia of the normal and
 * tangential directions, up to 3 nq square) | T (2 nq*nq: the responses to stuck points' tangential rows) |
 * L (9 nq*nq: the factor of the held rows' system). */
#define GAC_IMPACT_NWORK(nq, npoint, njrow, friction) \
    (((friction) ? 24L : 2L) * (nq) * (nq) + (nq) + 3L * (npoint) + GAC_AT_LEAST_1(njrow))
/* Doubles and ints of one simulation (gac_sim_init): dwork = x (nx = 2 nq) | p (nparam) | u (nu) | private;
 * iwork = resting (nq) | private.  The doubles: x, p, u and the controller's u, f, 16 stages, x1, xs, 8 dense-output
 * rows (28 nx in all), 9 per-contact doubles (7 arrays and the 2-vector slip), the impact work and an nq x nq
 * scratch; the ints: resting, then is_resting, n_shrink and is_stuck per contact. */
#define GAC_SIM_NDOUBLE(nq, nparam, nu, npoint, ncontact, njrow, friction) \
    (28L * 2 * (nq) + (nparam) + 2L * (nu) + 9L * GAC_AT_LEAST_1(ncontact) \
     + GAC_IMPACT_NWORK(nq, npoint, njrow, friction) + (long)(nq) * (nq))
#define GAC_SIM_NINT(nq, ncontact) ((long)(nq) + 7L * GAC_AT_LEAST_1(ncontact))
/* Doubles and ints of one impact record (gac_record_bind): dwork = impulse | q | qd_before | qd_after
 * (nq each) | impulse_t (2 nq), iwork = contact | landed | released | stuck | slipped (nq each). */
#define GAC_RECORD_NDOUBLE(nq) (6L * (nq))
#define GAC_RECORD_NINT(nq) (5L * (nq))

/* The macros above for model m. */
long gac_impact_nwork(const gac_model *m);
long gac_sim_ndouble(const gac_model *m);
long gac_sim_nint(const gac_model *m);
long gac_record_ndouble(const gac_model *m);
long gac_record_nint(const gac_model *m);

/* ---- kernels of the impact phase (no simulation state) ----------------------------------------- */

/* Impact law, Eq. 44-48: all `ncontact_set` contacts in `contact_set` (indices 0..ncontact-1) together, Newton
 * restitution e of each contact's wall, configuration unchanged.  Solved as
 *   (J I_f^-1 J^T) F = -(1 + e) J qd,   qd_plus = qd + I_f^-1 J^T F,
 * which is Eq. 48 with the velocity unknowns eliminated.  J rows are signed along the inward normal, so
 * impulse[k] > 0 (N s) pushes contact contact_set[k] away from its wall (a negative value pulls).
 * q, qd, p in; qd_plus (nq) and impulse (ncontact_set) out; work: gac_impact_nwork(m) doubles.
 * Returns GAC_OK or GAC_ERR_BAD_CONTACT, _SINGULAR_MASS, _SINGULAR_IMPACT, _GIMBAL_LOCK. */
int gac_impact(const gac_model *m, const double *GAC_RESTRICT q, const double *GAC_RESTRICT qd,
               const double *GAC_RESTRICT p, int ncontact_set, const int *GAC_RESTRICT contact_set,
               double *GAC_RESTRICT qd_plus, double *GAC_RESTRICT impulse, double *GAC_RESTRICT work);

/* The impact law with complementarity, for contacts at their walls that may approach, rest or separate:
 * impulses F >= 0 (no contact pulls), no contact approaches its wall afterwards, and the kinetic energy
 * never grows (it is kept exactly when every contact that takes an impulse has e = 1).  Solved in rounds:
 * in each, the contacts that approach (v < 0) or rest (v = 0) take part with
 *     0 <= F  _|_  v+ + e v- >= 0         (Newton's law, Eq. 47, with complementarity; e = 0 at rest),
 * until none approaches; a separating contact takes no impulse unless the others drive it into its wall,
 * and is then struck by its own law in the next round.  When every approaching contact pushes, one round
 * is Eq. 47 exactly (same result as gac_impact).  A contact is at rest in a round when |v| is below 1e-11 of the
 * fastest approach before, or below the round-off its velocity has gathered over the rounds (4 (k + 1) eps of the
 * sum of |v| and |A_ab F_b| of each update), so that rounds over nearly dependent rows, whose velocities carry
 * A's round-off times large impulses, neither strike a resting contact on noise nor go on for it.  After
 * GAC_MAX_ROUNDS rounds a plastic round over all contacts ends the sequence (rounds that cycle: contacts whose
 * rows meet at a sharp angle in the metric A, like a ball in a narrow wedge, strike each other in turn with
 * velocities that fall only slowly; at e < 1 the sequence converges to the plastic projection).  impulse[k]: total impulse of contact contact_set[k] (N s, >= 0).  Same arguments
 * as gac_impact; at most min(nq, GAC_LCP_CAP) contacts take part in one round (solved exactly by
 * enumerating the pushing sets; more: GAC_ERR_LCP). */
int gac_impact_complementarity(const gac_model *m, const double *GAC_RESTRICT q, const double *GAC_RESTRICT qd,
                               const double *GAC_RESTRICT p, int ncontact_set, const int *GAC_RESTRICT contact_set,
                               double *GAC_RESTRICT qd_plus, double *GAC_RESTRICT impulse,
                               double *GAC_RESTRICT work);

/* The impact law with Coulomb friction (at rough walls, link pairs and obstacles): gac_impact_complementarity's rounds, each round's problem on the
 * contacts that approach or rest being, for law GAC_IMPACT_LAW_GDI,
 *     xi = gamma+ + e gamma-,   0 <= Lambda_N _|_ xi_N >= 0,   Lambda_T = -c_f Lambda_N xi_T / |xi_T| (xi_T != 0),
 *     |Lambda_T| <= c_f Lambda_N (xi_T = 0),
 * gamma = (normal velocity, velocities along the wall's tangential axes) of a contact, Lambda its impulse, e its
 * wall's restitution (0 for a contact at rest), c_f its wall's friction coefficient (a stop or a frictionless wall:
 * no tangential part).  T+ - T- = Lambda^T (gamma+ + gamma-) / 2 <= 0: no energy gain, for any slip, stick or slip
 * reversal during the impact; c_f = 0 is Newton's law (Eq. 47).  A round whose contacts' different e would gain
 * energy is solved with their smallest e (*law_used GAC_IMPACT_LAW_GDI_COMMON_E).  GAC_IMPACT_LAW_NEWTON_COULOMB:
 * e on the normal velocity only (xi_T = gamma_T+), which can gain energy; GAC_IMPACT_LAW_FRICTIONLESS: c_f ignored.
 * Each round is solved by projected Gauss-Seidel with every contact's own problem solved exactly.
 * impulse[k] (N s, >= 0) along contact contact_set[k]'s inward normal, impulse_t[2k], impulse_t[2k + 1] (N s) along
 * its wall's two tangential axes in ascending order (X1, X2 for a X3 wall; 0 where the model has no motion or the
 * wall no friction), or a link pair's or obstacle's t1, t2 (its contact frame at the closest points: n, t1 = link
 * i's axis with its part along n removed, t2 = n x t1; its rows J^T n, J^T t1, J^T t2); *law_used the law applied (GAC_IMPACT_LAW_*), *residual the largest relative violation of the
 * law's conditions.  A model with no rough wall (its work array the smaller one) is solved by the frictionless law's
 * rounds whatever the law asked (*law_used GAC_IMPACT_LAW_FRICTIONLESS).  work: gac_impact_nwork(m) doubles.
 * Returns GAC_OK or GAC_ERR_BAD_CONTACT, _SINGULAR_MASS,
 * _GIMBAL_LOCK, _BAD_OPTION (law), _IMPACT_FRICTION (residual above GAC_FRICTION_RESIDUAL_MAX). */
int gac_impact_friction(const gac_model *m, const double *GAC_RESTRICT q, const double *GAC_RESTRICT qd,
                        const double *GAC_RESTRICT p, int ncontact_set, const int *GAC_RESTRICT contact_set, int law,
                        double *GAC_RESTRICT qd_plus, double *GAC_RESTRICT impulse, double *GAC_RESTRICT impulse_t,
                        int *law_used, double *residual, double *GAC_RESTRICT work);

/* Generalised accelerations with the resting contacts resting[0..nresting-1] held as bilateral constraints:
 * I_f qdd = R + N^T lambda, N qdd = -Ndot qd (N: Jacobian rows signed along the inward normal), solved as
 * qdd = qdd_free + I_f^-1 N^T lambda with (N I_f^-1 N^T) lambda = -(N qdd_free + Ndot qd).  On a wall with
 * Coulomb friction (has_friction) the point also takes -c_f lambda v_t / max(|v_t|, friction_velocity) along the
 * wall (v_t its velocity there): the system for lambda is then N I_f^-1 (N^T + c_f J_t^T (-phi)) lambda = ...,
 * not symmetric, and GAC_ERR_FRICTION where it is not a P-matrix (the Painleve paradox: B + B^T positive
 * definite suffices; otherwise, for up to 10 contacts, every principal minor is checked).
 * qdd (nq, rad/s^2 or m/s^2 by coordinate) and lambda (nresting) out; lambda[k] (N) is the force of contact
 * resting[k] along its inward normal (> 0 pushes); a contact whose row depends on the earlier ones' (held
 * by them already) gets lambda = 0.  work: gac_impact_nwork(m) doubles.  nresting = 0 gives
 * forward_dynamics.  u: the inputs (nu; may be NULL when nu = 0).  Returns GAC_OK or an error (< 0). */
int gac_constrained_dynamics(const gac_model *m, const double *q, const double *qd, const double *u,
                             const double *p, int nresting, const int *resting, double *qdd, double *lambda,
                             double *work);

/* Contact c's point index (1-based, O_1 = 1), wall axis (0..2 for X1..X3) and inward normal sign (+1/-1);
 * a joint stop: its joint k, axis -1 and +1 (lower) or -1 (upper); a link pair: its first link i, axis -1 and +1;
 * c outside 0..ncontact-1: 0, -1, 0. */
void gac_contact_info(const gac_model *m, int c, int *point, int *axis, int *normal_sign);

/* Two links as capsules (gac_link.c): link i spans O_i -> O_i+1.  The closest points of two segments a0-a1 and
 * b0-b1: a0 + s (a1 - a0) and b0 + t (b1 - b0), s, t in [0, 1]: the least distance to round-off (the middle of their
 * overlap where the distance is flat along it to 1e-12 of the lengths). */
void gac_segment_closest(const double *a0, const double *a1, const double *b0, const double *b1, double *s,
                         double *t);
/* The contact of links i and j (1-based, i != j, both in 1..npoint - 1) whose capsule radii add up to `radius` (m):
 * geometry (GAC_LINK_NGEOMETRY doubles) = gap (the segments' distance less radius, m; < 0: they overlap), s, t
 * (the closest points' fractions along links i and j) and the unit normal n (3) from link j's closest point to link
 * i's (when the axes cross, across both).  The gap's rate is n . (v_P - v_Q), P, Q the closest points moving with
 * their links.  Returns GAC_OK or GAC_ERR_BAD_CONTACT. */
int gac_link_gap(const gac_model *m, const double *q, const double *p, int i, int j, double radius,
                 double *geometry);
/* g (nq) = J^T n: the generalised force of a unit push along n on link i at P and -n on link j at Q, the row of
 * that contact (nq calls of contact_velocities: O(n^2)).  geometry from gac_link_gap.  Returns the row's scale,
 * the norm of the relative velocity v_P - v_Q's columns (a row far below it is round-off: no motion moves P, Q
 * along n). */
double gac_link_direction(const gac_model *m, const double *q, const double *p, int i, int j,
                          const double *geometry, double *g);
/* Newton's law (Eq. 47) on the relative normal velocity v = n . (v_P - v_Q) of links i and j, configuration
 * unchanged: an approaching pair (v < 0) takes the impulse F = -(1 + e) v / (n I_f^-1 n^T) >= 0 (N s, pushing them
 * apart), so that v+ = -e v; a separating one none.  qd_plus (nq), *impulse, and *v_normal (v before; may be NULL)
 * out.  Returns GAC_OK or GAC_ERR_BAD_CONTACT, _BAD_OPTION (e outside [0, 1]), _SINGULAR_MASS, _SINGULAR_IMPACT (the
 * chain cannot move along the row: the closest points are the two ends of the one link between i and j). */
int gac_link_impact(const gac_model *m, const double *q, const double *qd, const double *p, int i, int j,
                    double radius, double e, double *qd_plus, double *impulse, double *v_normal);

/* Link i (1-based) of radius `radius` (m; the link's own) and fixed obstacle o (0-based), its geometry at the
 * parameters p (gac_obstacle_shape): geometry (GAC_LINK_NGEOMETRY doubles) as gac_link_gap's for the sum of the two
 * radii, t along the obstacle's segment and n from the obstacle's closest point to the link's.  A box or a plane
 * (gac_obstacle.c): the least signed distance of the link's segment from it less `radius`, s* along the link, t = 0,
 * n the signed distance's gradient at that point; a link touching or reaching into a box: minus its depth (the
 * least translation parting them) less `radius`, n the depth's direction (a face's normal, or across the link and
 * an edge) and s* the link's point it is measured at.  The gap's rate is n . v_P either way (the obstacle does not
 * move).  Returns GAC_OK or GAC_ERR_BAD_CONTACT. */
int gac_obstacle_gap(const gac_model *m, const double *q, const double *p, int i, int o, double radius,
                     double *geometry);
/* The geometry (GAC_LINK_NGEOMETRY doubles, as gac_link_gap's and gac_obstacle_gap's) of contact c of the model's
 * table, a link pair or an obstacle's contact: its gap less its radii, s, t and n, for an obstacle's contact of one
 * joint point (gac_contact.end) that point's (s = 0 or 1 along its link).  Returns GAC_OK, GAC_ERR_NULL_ARGUMENT or
 * GAC_ERR_BAD_CONTACT (c outside the table, or a wall's or a stop's). */
int gac_contact_geometry(const gac_model *m, const double *q, const double *p, int c, double *geometry);
/* Obstacle o's shape row at the parameters p (GAC_OBSTACLE_NSHAPE doubles, the layout of m->obstacle_shapes): its
 * geometry from p where m->obstacle_params gives its place, else the model's constants.  Returns GAC_OK or
 * GAC_ERR_BAD_CONTACT (o out of range) or GAC_ERR_NULL_ARGUMENT. */
int gac_obstacle_shape(const gac_model *m, const double *p, int o, double *shape);
/* The obstacle (0..nobstacle-1) whose geometry parameter p[index] is, or -1 (not an obstacle's geometry). */
int gac_obstacle_parameter(const gac_model *m, int index);
/* g (nq) = J^T n of contact c (0..ncontact-1, any kind): the generalised force of a unit push along its normal (a
 * wall's or stop's signed Jacobian row; a link pair's or obstacle's at the closest points), so that the gap's rate
 * is g . qd.  Returns GAC_OK or GAC_ERR_BAD_CONTACT (c out of range, or a link contact's geometry failed). */
int gac_contact_normal(const gac_model *m, const double *q, const double *p, int c, double *g);
/* The derivatives of a link pair's or an obstacle contact's gap and of its J^T n along a direction (dq (nq),
 * dp (nparam)), for the sensitivities' impact: *dgap, g (nq) = J^T n (gac_contact_normal) and dg (nq) = d(J^T n).
 * The closest points' motion (an interior fraction moves, an end point's stays) and the unit normal's rotation are
 * differentiated in closed form; the points' Jacobians' own change (second derivatives of the kinematics) and the
 * points' motion by the model's contact_velocities_tangent and contact_points_tangent (exact), or, in a descriptor
 * without them, by fourth-order central differences of contact_velocities and contact_points (~1e-12 of their
 * size).  Returns GAC_OK, GAC_ERR_NULL_ARGUMENT,
 * GAC_ERR_BAD_CONTACT (c not a link pair or obstacle contact, or its geometry failed) or GAC_ERR_LINK_CONTACT where
 * they have no derivative: the axes crossing (distance 0), or parallel with both closest points inside.  A box's or
 * plane's face has a constant normal and the link's closest point at one of its ends (a link parallel to the face,
 * a whole stretch closest: GAC_ERR_LINK_CONTACT); a box's edge or corner nearest is a fixed segment or point, as a
 * bar's or a sphere's.  dp may move an obstacle whose geometry is among the parameters: a sphere's centre and
 * radius, a bar's ends and radius, a box's centre and half extents, a plane's point (the part of it the gap is
 * measured from moves, a radius lowers the gap; the obstacle's own J stays 0); along a box's rotation entry or a
 * plane's normal entry (no direction of its own: the rotation stays orthonormal, the normal unit) it returns
 * GAC_ERR_BAD_OPTION. */
int gac_contact_normal_tangent(const gac_model *m, const double *q, const double *p, int c, const double *dq,
                               const double *dp, double *dgap, double *g, double *dg);
/* A link pair's or an obstacle contact's frame rows and their derivatives along (dq (nq), dp (nparam)): axes (9)
 * the frame n, t1, t2 row by row (t1 link i's axis off n, t2 = n x t1: the frictional impact law's and the resting
 * friction's frame), g (3 nq) the rows J^T n, J^T t1, J^T t2 (the closest points' relative velocity along each is
 * g_k . qd) and dg (3 nq) their derivatives, as gac_contact_normal_tangent's for the normal (its dg is dg's first
 * row) with the tangents' turning d t1 = (I - t1 t1^T) du / |u| (u = d1 - (d1 . n) n, d1 link i's axis),
 * d t2 = dn x t1 + n x d t1.  Along dq = qd (dp = 0), dg_k . qd is the bias of a resting contact's row k:
 * d/dt (g_k . qd) = g_k . qdd + dg_k . qd.  Returns as gac_contact_normal_tangent. */
int gac_contact_frame_tangent(const gac_model *m, const double *q, const double *p, int c, const double *dq,
                              const double *dp, double *axes, double *g, double *dg);

/* The base chart's measure chi(q) (gac_chart), in [0, 1] for the default twists; of several turning bases
 * (gac_model.nbase), the smallest of theirs. */
double gac_chart_measure(const gac_model *m, const double *q);

/* Message for a return code (a static string). */
const char *gac_error_message(int code);

/* ---- the two base charts (gac_chart.c) ------------------------------------------------------------ */
/* Chart A is a model's own base parametrisation (gac_base), chart B the same with T_-1 replaced by C T_-1
 * (gac_model.chart_b).  Link 1's frame, the inner joint angles theta_2..theta_n and the base position X are the
 * same in both; only (theta_-1, theta_0, theta_1) and their rates differ, through the orientation R = ^{ref}R_1
 * and the angular velocity omega = E thetadot, which both charts share.  Because C turns u_-1 by a right angle,
 * z_1 cannot be near both charts' first axes: on B (chi_A <= 2 chart_switch <= 0.7) chi_B >= sqrt(1 - 0.7^2). */
#define GAC_CHART_SWITCH_MIN 0.1
#define GAC_CHART_SWITCH_MAX 0.35
#define GAC_CHART_LOCK 1e-12    /* a measure below this is the chart's own lock: theta_-1 is kept from `near` */
#define GAC_CHART_BASES_MAX 4   /* a model switches the charts of at most this many bases (2^4 chart models) */

/* R = T_-1 Rz(angles[0]) T_0 Rz(angles[1]) T_1 Rz(angles[2]) (3 x 3, row-major). */
void gac_base_rotation(const gac_base *c, const double *angles, double *R);
/* E (3 x 3, row-major): its columns the joint axes u_-1, u_0, u_1 in the reference frame; omega = E thetadot. */
void gac_base_axes(const gac_base *c, const double *angles, double *E);
/* The chart's measure |det E| = |u_-1 x z_1| of an orientation R (given in any chart), in [0, 1]. */
double gac_base_measure(const gac_base *c, const double *R);
/* The angles of orientation R on chart c, in closed form: of the two solutions (theta_0 on either side of the
 * lock) and their 2 pi shifts, the one nearest `near` (sum of the three distances); near NULL: the principal one
 * (theta_0 - phi in [-pi, 0], phi the lock angle), wrapped to (-pi, pi].  At the chart's lock (measure below
 * GAC_CHART_LOCK) only theta_-1 +- theta_1 is defined: theta_-1 is near[0] (0 without near).  Checked by
 * recomposing R: GAC_OK, or GAC_ERR_BAD_MODEL (T_0 or T_1 does not turn its axis a right angle). */
int gac_base_angles(const gac_base *c, const double *R, const double *near, double *angles);
/* The rates with E(angles) rates = omega; at the chart's lock (|det E| below GAC_CHART_LOCK) the least-squares
 * rates of least norm. */
void gac_base_rates(const gac_base *c, const double *angles, const double *omega, double *rates);
/* A state x = [q, qd] (2 nq) of the chart `from` as the same motion on the chart `to`: R and omega kept, the base
 * angles from gac_base_angles (near: as there, `to`'s angles to continue from) and their rates from
 * gac_base_rates; every other coordinate and rate copied.  Both charts must keep the three angles as coordinates
 * at the same indices.  x and out may be the same array.  GAC_OK or GAC_ERR_BAD_MODEL. */
int gac_chart_convert(const gac_base *from, const gac_base *to, int nq, const double *x, const double *near,
                      double *out);
/* The derivative of that conversion, applied to k directions S (k x 2 nq, direction-major, in place: dx on `from`
 * in, dy on `to` out), at x (on `from`) and y (its conversion).  The base angles and rates (a on `from`, b on `to`):
 *     E_b(b) db = E_a(a) da                                   (the same angular displacement: R kept)
 *     E_b db' = dE_a[da] a' + E_a da' - dE_b[db] b'           (E_b b' = E_a a' = omega, differentiated)
 * dE v = v[1] du_0 + v[2] du_1 as the axes turn about those before them, du_0 = (u_-1 dtheta_-1) x u_0,
 * du_1 = (u_-1 dtheta_-1 + u_0 dtheta_0) x u_1 (u_-1 fixed); every other component copied.  GAC_OK, GAC_ERR_BAD_MODEL (the angles' indices, as
 * gac_chart_convert) or GAC_ERR_GIMBAL_LOCK (y at `to`'s lock: |det E_b| below GAC_CHART_LOCK). */
int gac_chart_convert_tangent(const gac_base *from, const gac_base *to, int nq, const double *x, const double *y,
                              int k, double *S);

/* ---- the hybrid simulation -------------------------------------------------------------------- */
/*
 * Events.  Each accepted step's interpolant is sampled at opt.event_samples points; an impact is a gap
 * crossing zero with the point approaching its wall, located to opt.event_tol.  A dip through the wall and
 * back between two samples (gap > 0 at both) is found where the gap's rate, the normal velocity, changes
 * sign: if the gap at that minimum is below -(atol + rtol l) (l: the largest |coordinate| of the points;
 * 0 for RK4) the crossing before it is the impact; a shallower minimum, a touch with normal velocity 0
 * within the integration error, is a graze and no impact.
 *
 * Impacts.  Every contact within contact_tol of its wall, every approaching one within the simultaneity
 * window (100 x the adaptive method's position tolerance, or contact_tol if larger) and every resting
 * one take part.  The law (gac_impact_complementarity) is Newton's law, Eq. 47, with complementarity, in
 * rounds until no contact approaches: F >= 0, no energy gain, e = 1 keeps the energy exactly; a contact
 * that separates takes an impulse only if the others drive it into its wall.  Where a contact taking part is on
 * a wall with Coulomb friction (c_f > 0), each round is the frictional law of opt.impact_law (gac_impact_friction;
 * by default Coulomb's cone on gamma+ + e gamma-, which never gains energy; record.law, impulse_t, residual).  Its post-conditions are
 * checked to the law's round-off bound (record.roundoff; GAC_ERR_IMPACT_ACCURACY otherwise), and that bound must
 * not exceed GAC_IMPACT_ROUNDOFF_MAX (1e-2): an impact known only to a larger error of its energy stops the run
 * (GAC_ERR_IMPACT_ACCURACY, record.roundoff says its bound), as does the plastic closing round of
 * a sequence of rounds on walls that all have e = 1.
 *
 * Resting contact (Zeno behaviour).  With e < 1 and gravity, impacts of a point on a wall accumulate
 * (the bounces shrink geometrically).  At an impact on a wall with e < 1, a contact whose bounce would rise
 * less than opt.rest_height (v+^2 <= 2 a rest_height, a = its normal acceleration towards the wall), or
 * that has had opt.zeno_impacts impacts at shrinking intervals, LANDS: it is struck with e = 0 (a plastic
 * impact, still F >= 0), and if it ends at rest it becomes a RESTING contact, held at the gap it landed at (no
 * position moves at an impact), a bilateral, frictionless constraint of the flight equations,
 *     I_f qdd = R + N_a^T lambda,    N_a qdd = -Ndot_a qd     (N_a: signed Jacobian rows of the resting set),
 * with positions and velocities projected back onto the constraint (gaps to their held values, normal
 * velocity = 0, mass metric; no free contact pushed deeper into its wall) after every accepted step.
 * record.energy_rest is the kinetic energy the landings took.  On a wall with e = 1 a contact lands only
 * if that energy is round-off.  A resting contact is released when its force lambda (along the inward
 * normal) falls through 0: that crossing is located on the dense output like a wall crossing.
 * Only forces lambda > 0 are kept (an acceleration-level complementarity solve when the set changes), and
 * only contacts with independent rows (a dependent one is held by the others; one that becomes dependent
 * in flight gets lambda = 0 and is released).  A resting contact takes part in another impact with its
 * own e; one the impact lifts by less than rest_height stays, one lifted higher is released.
 * gac_sim_init also puts at rest the contacts that start at their wall (gap <= contact_tol) with a normal
 * velocity under the same bound and a positive force (a chain started at rest on the floor).
 * Every landing and release is reported in the record (landed[], released[]).
 *
 * Sticking (opt.stick = 1, the default).  A point resting on a wall with Coulomb friction c_f > 0 is STUCK or
 * SLIDING, and so is a rough link pair or link on an obstacle at rest, along its contact frame: its tangential rows
 * are g_k = J_P^T t_k - J_Q^T t_k (k = 1, 2: the closest points' relative velocity along the frame's t1, t2, as at its
 * impacts), their biases dg_k(qd) . qd the exact derivative of the frame rows (gac_contact_frame_tangent), where a
 * wall's are its Jacobian rows trow and their contact_bias rows.  Stuck: its tangential rows (a wall's
 * gac_contact.trow) are held with the normal rows as bilateral constraints, J_t qdd + Jdot_t qd = 0, their forces lambda_T solved with the normal forces in one system (rows
 * dependent on the others share the force by the least-norm solution, e.g. a rod lying flat).  Sliding: the force
 * -c_f lambda phi, phi = v_t / max(|v_t|, v_s) (v_s = friction_velocity), with, just after a slip began and while
 * the point is slower than v_s, (1 - |v_t| / v_s) d added to phi along the slip's direction d (the friction
 * continues from c_f lambda_N opposite d; d is forgotten at a step's end where the point is faster than v_s or moves
 * against it).  Stuck -> sliding: when |lambda_T| reaches
 * c_f lambda_N, located on the dense output like a release (the event value lambda_N - |lambda_T| / c_f falling
 * through 0), the slip starting along -lambda_T; a force lambda_N falling through 0 first releases it.  Sliding ->
 * stuck: at an accepted step's end, after an impact (every resting point re-decided) and at the start, a point
 * slower than v_s along its wall (or whose one tangential velocity changed sign within the step) whose stuck solve
 * gives |lambda_T| <= c_f lambda_N (and keeps the other stuck points inside their cones); its tangential velocity is
 * then projected to 0 in the mass metric, the kinetic energy that takes added to loss_friction.  The projection
 * after every step holds stuck points' tangential velocities at 0 too.  Every transition is recorded like a landing
 * or a release: record.stuck[] (came to stick) and record.slipped[] (began to slip), with the impact that caused it
 * (a point stuck before an impact and stuck after it made no transition; one stuck before and sliding after it
 * slipped), or else as its own GAC_SIM_CONTACT event (a slip located on the dense output, a stick at a step's end:
 * qd_before, energy_before the state before the stick's projection, qd_after, energy_after after it; the contacts
 * gac_sim_init puts at rest and sticks, with their first report).  sim.n_sticks and sim.n_slips count them.  The
 * stuck constraint does no work.
 *
 * Tangential impact (gac_jam.c).  Where resting points slide on rough walls and their system B is no P-matrix (the
 * Painleve paradox: one contact, its compliance with sliding B_aa <= 0), the loop takes an impact without collision:
 * the GDI law on the resting contacts' normal and tangential rows with their normal velocities 0 and e = 0, its
 * non-trivial solution (some normal impulse > 0, the first of the contacts' modes enumerated from all stuck on; for
 * one contact the stick impulse -W^-1 gamma-, inside the cone exactly where B_aa <= 0).  Its post-conditions: every
 * impulse >= 0, T+ <= T- (1 + 1e-10).  Afterwards contacts left at rest stick where their cones hold them and are
 * re-checked at the next advance (one that would pull is released), a contact the impulse lifts is released.  It is
 * taken where the state itself has no consistent forces (the start: gac_sim_init accepts it and the first advance
 * after the contact event takes it; after a landing or a change of the inputs), and at the dynamic jam: sliding
 * smoothly towards B_aa = 0 the normal force grows without bound, the trial stages beyond fail (GAC_ERR_FRICTION
 * in a stage rejects the step; RK4 halves it), and where the steps underflow onto that instant the impact is taken
 * if it has a non-trivial solution there.  The record's law is GAC_IMPACT_LAW_GDI_TANGENTIAL (complementarity 1);
 * sim.n_tangential_impacts counts them (within n_impacts).  Before the impact, two other solutions of the paradox
 * are taken where they exist (sim.n_painleve_choices counts them): at (nearly) zero speed, a point slower than
 * friction_velocity whose slip direction has no consistent forces slides without one (phi = v_t / v_s; a slow point
 * that cannot stick takes its stuck solve's slip direction d only where the forces exist with it, else -d, else, in
 * 3D, the directions across d, else none), and where the state itself has no consistent forces but some contacts may
 * leave (held on a subset with consistent forces >= 0, every released contact's normal acceleration >= 0: the
 * indeterminacy), the subset of least total normal force is kept and the others released (GAC_SIM_CONTACT).  A step
 * whose dense output passes a state without consistent forces is rejected and shrunk like a failed stage.
 * Where one contact's law has no non-trivial solution, the impulse of its cone that takes the most kinetic energy
 * (min L.gamma- + L W L / 2 over |L_T| <= c_f L_N) is taken instead.  GAC_ERR_FRICTION stops the run only where none
 * of these applies (several contacts, more than 6, or a trivial impulse), or the state after it still has no
 * consistent forces.
 *
 * Inputs.  The inputs u (nu) are held over each gac_sim_advance call (a zero-order hold, the convention of
 * FMI co-simulation): change them between calls with gac_sim_set_input, so that a change falls on a step
 * boundary.  Or give a controller (gac_sim_set_controller): the loop then asks it for u at every stage.
 * The energy the inputs put in and the dampers take out is integrated over every step on the dense output
 * (5-point Gauss-Legendre on the step's interpolant): sim.work_input, sim.loss_damping; with the impacts'
 * losses they close the energy balance E(t) - E(0) = work_input - loss_damping - (impact losses).
 *
 * Energy balance.  The loop keeps the balance's residual (J)
 *     sim.energy_residual = E - E(0) - work_input + loss_damping + loss_friction + loss_impacts,
 * E = T + V at the current state, and checks it at every step end (after the projection onto the resting
 * contacts) and after every impact: beyond energy_tol x sim.energy_scale (the largest of M g L, the model's
 * weight_scale, and T + |V| at a step end so far, plus |work_input| + loss_damping + loss_friction +
 * loss_impacts), plus what the impacts' laws may change by round-off (sim.energy_roundoff, the sum of each
 * record's roundoff x T), the run stops with GAC_ERR_DRIFT at that state.  opt.energy_tol < 0 (default) is
 * min(0.1, max(1e-8, 1e4 rtol)) for the adaptive methods, a budget of 1e4 steps' worth of tolerance, and off for RK4; 0 turns the check off.  What a projection onto
 * the resting contacts changes in E is in the residual (it should keep the energy) and summed in
 * sim.energy_projection; one that changes E by more than energy_tol x energy_scale / 10 stops the run with
 * GAC_ERR_PROJECTION.  The adaptive methods also hold each step's own energy error to the tolerance where the
 * flight is free and conservative (no power kernel, no resting contact): |E(x1) - E(x0)| / (rtol x
 * energy_scale / 10) enters the step's error norm (the larger of the two decides), as the error of each
 * component alone does not bound the energy's, which accumulates over many steps.
 *
 * Base charts.  With a second chart (gac_model.chart_b) and opt.chart_switch > 0, the loop leaves chart A at
 * the end of an accepted step where chi_A < chart_switch (at the start of the run too) and comes back at the end
 * of one where chi_A > 2 chart_switch: the state is converted (gac_chart_convert) and the integrator restarts from
 * it with a fresh first step.  A step whose end falls below the chart's floor, or whose theta_0 passes the lock,
 * is rejected and retried shorter (RK4: the switch is made at its start).  Resting contacts, held gaps, the
 * work integrals and the counters carry over.  Samples, impact records and gac_sim_state are in chart A's
 * coordinates, whichever chart was integrated; sim.chart and sim.n_chart_switches say which and how often.
 * A model of several chains turning their bases (gac_model.nbase, chart_models) does this for each base on its
 * own, with its own chi_A: sim.chart is then a mask (bit j: base j on its chart B), a switch converts the bases
 * that cross their thresholds at that step end and continues on the model of the new mask, and the floor holds
 * for every base's measure on the chart it is on.
 *
 * Stops before trouble: GAC_ERR_GIMBAL_LOCK (the base chart's measure below sqrt(16 eps / rtol) and no second
 * chart to continue on: chart_switch 0, or a model without chart_b), GAC_ERR_UNSTABLE (RK4 past its stability,
 * sim.rk4_h_rho), GAC_ERR_LOST_CONTACT,
 * GAC_ERR_MAX_STEPS (sim.err_index names the state component that limits the step), GAC_ERR_WALL_TIME
 * (opt.max_wall_time of the run's clock used), GAC_ERR_STOPPED (the progress callback said stop),
 * GAC_ERR_DRIFT and GAC_ERR_PROJECTION (the energy balance, above).
 */

/* An input schedule: values u_k (nu each) at breakpoints t_k (n >= 1, strictly increasing), held (linear = 0:
 * u(t) = u_k for t_k <= t < t_k+1) or interpolated linearly between the breakpoints (linear = 1); u_0 before t_0 and
 * u_(n-1) after t_(n-1).  The caller owns both arrays. */
typedef struct {
    int n;                /* number of breakpoints */
    int nu;               /* inputs per breakpoint */
    const double *t;      /* [n] breakpoints (s) */
    const double *u;      /* [n * nu] values, row k at u + k nu */
    int linear;           /* 0: held, 1: linear between the breakpoints */
} gac_schedule;

typedef struct {
    int method;            /* GAC_METHOD_RK4, GAC_METHOD_DOPRI5 (default) or GAC_METHOD_DOP853 */
    double dt;             /* RK4 step (s); for the adaptive methods the first step, 0 = automatic */
    double rtol, atol;     /* adaptive methods: relative and absolute tolerances (default 1e-8, 1e-10);
                              GAC_RTOL_MIN <= rtol < 1 (below, round-off stops the steps), atol > 0 */
    double h_max;          /* largest step (s), 0 = unbounded */
    int event_samples;     /* interpolant samples per step searched for wall crossings (default 4); a dip
                              through a wall between two samples is found at the gap's minimum */
    double event_tol;      /* time tolerance of event location on the interpolant (default 1e-13 s) */
    double contact_tol;    /* approaching contacts within this gap (m) join a simultaneous impact (1e-6) */
    long max_steps;        /* steps allowed per advance call, 0 = unbounded (default 10^7) */
    double rest_height;    /* m: a bounce rising less than this ends in resting contact; < 0 (default):
                              10 contact_tol; 0: never by this rule */
    int zeno_impacts;      /* resting after this many impacts of one contact at shrinking intervals
                              (default 20; 0: never by this rule) */
    double max_wall_time;  /* s of the run's clock (gac_sim_set_clock) allowed since gac_sim_init or the last
                              gac_sim_set_clock, looked at every GAC_LOOK_STEPS steps and at the start of every
                              advance: GAC_ERR_WALL_TIME beyond it.  0 (default): unbounded */
    long max_impacts;      /* impacts allowed since gac_sim_init: once applied, gac_sim_advance returns
                              GAC_ERR_MAX_IMPACTS before the next step (impact accumulation; default 10000).
                              0: unbounded */
    double energy_tol;     /* the energy balance's allowed residual, relative to the run's energy scale (see
                              "Energy balance" above): GAC_ERR_DRIFT beyond it.  < 0 (default): automatic,
                              min(0.1, max(1e-8, 1e4 rtol)) for the adaptive methods and off for RK4 (a fixed
                              step has no tolerance to hold it to); 0: off; else 0 < energy_tol < 1 */
    double chart_switch;   /* a model with a second base chart (gac_model.chart_b) integrates on it where chart A's
                              measure chi_A falls below this, and back on A where chi_A exceeds twice this (the
                              hysteresis); 0: never (GAC_ERR_GIMBAL_LOCK near the lock), else within
                              [GAC_CHART_SWITCH_MIN, GAC_CHART_SWITCH_MAX] (default 0.3) */
    int impact_law;        /* the impact law at walls with Coulomb friction: GAC_IMPACT_LAW_GDI (default; never
                              gains energy), GAC_IMPACT_LAW_NEWTON_COULOMB (can gain energy: the run then stops with
                              GAC_ERR_IMPACT_ENERGY) or GAC_IMPACT_LAW_FRICTIONLESS (friction only on resting
                              contacts) */
    int stick;             /* 1 (default): a point resting on a wall with friction is STUCK (its tangential rows
                              held as constraints, see "Sticking" above) or SLIDING; 0: every resting point slides
                              against the regularised force alone (sticking only approximated by it) */
} gac_options;

/* What gac_sim_advance reports.  Scalars are fields; the arrays (nq entries each) point into the arrays
 * given to gac_record_bind. */
typedef struct {
    double t;                    /* impact time (s) */
    int ncontact;                /* simultaneous contacts */
    int *contact;                /* their indices 0..ncontact-1 of the model (see gac_contact_info) */
    double *impulse;             /* impulse along the inward normal (N s), >= 0 */
    double *impulse_t;           /* 2 per contact: impulse along its wall's two tangential axes, ascending, or
                                    a link pair's or obstacle's t1, t2 (gac_impact_friction) (N s; 0 without
                                    friction) */
    int law;                     /* the impact law applied (GAC_IMPACT_LAW_*: FRICTIONLESS when no contact with
                                    friction took part) */
    double residual;             /* the frictional law's largest relative violation of its conditions (0 without
                                    friction) */
    double energy_before, energy_after;   /* T + V (J) */
    double *q;                   /* configuration at impact */
    double *qd_before, *qd_after;
    int complementarity;         /* 1 if the result is not Eq. 47 over the approaching contacts (a contact
                                    took no impulse, or more than one round) */
    int rounds;                  /* rounds of the impact law (1 for Eq. 47 with complementarity) */
    int plastic;                 /* 1 if GAC_MAX_ROUNDS rounds ended in a plastic round */
    int law_elastic;             /* 1 if the law with each contact's own e (before landings) was elastic: only
                                    contacts with e = 1 took impulses, no plastic round; it then keeps the
                                    kinetic energy, to roundoff (energy_after + energy_rest = energy_before) */
    double energy_rest;          /* kinetic energy (J) the landings took: the law with each landing contact's
                                    own e minus the law with e = 0 (dropped bounces that would rise less
                                    than rest_height) */
    double roundoff;             /* the law's relative round-off bound on the energy (>= 1e-10), the tolerance
                                    of its post-conditions: the solves' error on the velocity change, holding
                                    landed contacts included, and the error of evaluating T itself (grows with
                                    cond(I_f) and with velocities along its soft directions) */
    int roundoff_cause;          /* roundoff's largest part (GAC_ROUNDOFF_*) */
    int refusal;                 /* with GAC_ERR_IMPACT_ACCURACY: the check that refused it (GAC_REFUSED_*) */
    double approach_before;      /* largest |normal velocity| of any contact before (m/s) */
    double approach_after;       /* fastest approach of a contact within contact_tol after (m/s) */
    int nlanded, *landed;        /* contacts come to rest at this event */
    int nreleased, *released;    /* resting contacts released at this event */
    int nstuck, *stuck;          /* resting contacts on rough walls that came to stick at this event (sliding -> stuck,
                                    or landed and stuck; see "Sticking"): sim.n_sticks counts them */
    int nslipped, *slipped;      /* stuck resting contacts that began to slip at this event (stuck -> sliding: their
                                    cone's edge reached, or an impact that set them sliding): sim.n_slips counts them */
} gac_impact_record;

/* The state of one simulation.  Read t, x, the counters and the resting set; write nothing but
 * opt.max_steps between gac_sim_advance calls.  x and p point into dwork, resting into iwork. */
typedef struct {
    gac_options opt;
    double t;                    /* current time (s) */
    double *x;                   /* current state [q, qd] (nx) */
    double *p;                   /* the parameters (nparam, a copy) */
    long n_steps, n_rejected, n_rhs, n_impacts;
    int nresting;                /* resting contacts: their indices resting[0..nresting-1] */
    int *resting;
    long n_landings, n_releases;
    int err_index;               /* state component (0..nx-1) that dominated the error estimate of the last
                                    adaptive step: what limits the step size */
    double *u;                   /* the inputs held over the next advance call (nu; gac_sim_set_input) */
    double work_input;           /* J: work of the inputs since gac_sim_init, int u . qd_actuated dt */
    double loss_damping;         /* J: energy the joint dampers took since gac_sim_init, int C theta_dot^2 dt */
    double loss_friction;        /* J: energy sliding friction took since gac_sim_init, int c_f lambda |v_t| ... dt */
    double wall_time;            /* s of the run's clock used, as of the last look (GAC_LOOK_STEPS) */
    double rk4_h_rho;            /* RK4: h rho of the last step, rho the rate of the chain's fastest mode seen in it
                                    (the stability rule: 3 steps in a row above 2.5, or one above 10, stop the run
                                    with GAC_ERR_UNSTABLE) */
    long n_slow_sliding;         /* accepted steps begun with a point resting on a wall with friction and sliding
                                    slower than GAC_SLOW_SLIDING friction_velocity, where the regularisation is
                                    stiff (time constant about friction_velocity / (c_f g)) and may limit the step */
    double t_slow_sliding;       /* s: the time those steps covered */
    long n_sticks, n_slips;      /* resting points on rough walls that came to stick (sliding -> stuck, at a step
                                    end, an impact or the start) and that began to slip (stuck -> sliding): the
                                    records' stuck[] and slipped[] entries */
    long n_tangential_impacts;   /* tangential impacts (record.law GAC_IMPACT_LAW_GDI_TANGENTIAL) since gac_sim_init:
                                    the Painleve paradox of sliding resting contacts resolved by an impact (also
                                    counted in n_impacts) */
    long n_painleve_choices;     /* slow resting points that could not stick and whose slip direction had no
                                    consistent normal forces (the Painleve paradox at zero speed, where the direction
                                    is free): each rejected direction, the next one taken (gac_try_stick) */
    double energy_initial;       /* J: T + V at gac_sim_init */
    double loss_impacts;         /* J: energy the impacts took since gac_sim_init, sum of energy_before - energy_after */
    double energy_roundoff;      /* J: what the impacts' energies are known to, sum of roundoff x T before each */
    double energy_projection;    /* J: energy change of the projections onto the resting contacts since gac_sim_init
                                    (part of energy_residual: a projection should keep the energy) */
    double energy_residual;      /* J: the energy balance at the current state, E - energy_initial - work_input
                                    + loss_damping + loss_friction + loss_impacts */
    double energy_scale;         /* J: what energy_residual is measured on: the largest of M g L (weight_scale) and
                                    T + |V| at a step end so far, plus |work_input| + loss_damping + loss_friction + loss_impacts */
    int chart;                   /* the base chart integrated now: 0 = A (the model given to gac_sim_init), 1 = B
                                    (its chart_b); of several turning bases, bit j set where base j is on its
                                    chart B (the model chart_models[chart]).  x is in this chart's coordinates;
                                    gac_sim_state, the samples and the impact records are always in chart A's */
    long n_chart_switches;       /* switches of a base between its charts since gac_sim_init (the start on B
                                    included; two bases switched at once count two) */
    int lost_contact;            /* GAC_ERR_LOST_CONTACT: the contact found beyond its wall (-1: none so far) */
    double lost_t, lost_gap;     /* s, m: where it was found (an event sample, a pass-through's point inside the
                                    body, or an impact) and its gap there */
    double lost_depth;           /* m: the depth allowed there, contact_tol + the simultaneity window */
    double lost_step[2];         /* s: the start and end of the step in which it was found */
    /* private: the model, integrator state and scratch (pointers into dwork / iwork) */
    const gac_model *model;      /* the model integrated now: model_a, model_a->chart_b, or chart_models[chart] */
    const gac_model *model_a;    /* the model given to gac_sim_init (chart A) */
    double near_a[12];           /* [3 GAC_CHART_BASES_MAX]: each base's chart A angles at the last step end (on B),
                                    sample or chart switch: the branch and 2 pi shift of the next conversion to
                                    chart A continue from them */
    gac_controller controller;   /* NULL: the held inputs u */
    gac_controller_jacobian controller_jacobian; /* NULL: none (gac_sim_set_controller_jacobian) */
    const gac_schedule *schedule; /* NULL: none (gac_sim_set_schedule) */
    void *controller_data;
    gac_clock clock;             /* NULL: clock() */
    void *clock_data;
    gac_progress progress;       /* NULL: none */
    void *progress_data;
    double wall_start;           /* the clock's reading when the budget started */
    long n_look;                 /* steps since the last look */
    double *u_eval;              /* nu: the controller's output at the current evaluation */
    int input_changed;           /* gac_sim_set_input (or a tangential impact) since the last advance: resting
                                    contacts re-checked */
    double h;
    int f_valid;
    double *f, *k[16], *x1, *xs, *cont[8];
    double t0_step, h_step;
    double *ev, *es, *eprev;     /* event values */
    double *vn;                  /* normal velocities at x, if vn_valid (event search) */
    int vn_valid;
    double *work;                /* gac_impact_nwork doubles */
    double *sub;                 /* nq*nq doubles: sub-problems of the resting contacts */
    double rest_height;          /* resolved opt.rest_height */
    double lever;                /* max(1 m, the chain's length): |dO/dq| bound */
    int *is_resting, pending, fail, fail_seen, n_unstable;
    int *is_stuck;               /* per contact: 1 if it rests stuck (its tangential rows held; opt.stick) */
    int *partner;                /* 4 per contact: the contacts that measure what it does where it is redundant
                                    (a link's or a pair's ends'), found at init */
    double *slip;                /* 2 per contact: the unit direction a point began to slip in (along its wall's
                                    tangential axes), the friction's direction while it is slower than
                                    friction_velocity; 0 when none */
    int *n_shrink;               /* impacts of each contact at shrinking intervals */
    double *t_last, *dt_last;
    double *gap_held;            /* gap (m) a resting contact is held at: its gap when it landed (within
                                    contact_tol, or the integration's position error below its wall) */
    double energy_x;             /* J: T + V at x (kept by gac_energy_check) */
    double energy_x1[2];         /* J: T and V at s->x1 (a step's end, or the state an impact left), if
                                    energy_x1_valid */
    int energy_x1_valid;
    double energy_tol;           /* resolved opt.energy_tol (0: off) */
    struct gac_sens_s *sens;     /* the sensitivities carried along (gac_sens_attach), NULL: none */
} gac_sim;

/* Default options (DOPRI5, rtol 1e-8, atol 1e-10, resting contact on).  opt NULL: nothing is done. */
void gac_default_options(gac_options *opt);

/* GAC_OK if every option is in its range, else GAC_ERR_BAD_OPTION with *field (if field is not NULL) a static
 * string naming the first option out of range and what it allows ("rtol: must be within [1e-14, 1) ..."); NULL opt:
 * GAC_ERR_NULL_ARGUMENT.  gac_sim_init applies it. */
int gac_check_options(const gac_options *opt, const char **field);

/* Start a simulation of model m at time t0 from (q, qd) with parameters p (copied into dwork), inputs 0 and
 * no controller.  Contacts
 * resting at their wall come to rest (reported by the first gac_sim_advance, GAC_SIM_CONTACT).
 * dwork: gac_sim_ndouble(m) doubles, iwork: gac_sim_nint(m) ints, owned by the caller for the life of sim.
 * Pointers: sim, m, dwork, iwork, q and qd must not be NULL (GAC_ERR_NULL_ARGUMENT); opt NULL means the
 * default options (gac_default_options), p NULL the model's default_parameters.
 * Refused: an inconsistent model (GAC_ERR_BAD_MODEL); options out of range (GAC_ERR_BAD_OPTION); a parameter
 * not finite, or outside its range or relations (m->check_parameters; GAC_ERR_BAD_PARAMETER, gac_check_parameters
 * says which); t0, q or qd not finite (GAC_ERR_BAD_OPTION); a contact point beyond its wall,
 * gap < -(contact_tol + w + 1e-12 max(1 m, l)) (GAC_ERR_START_OUTSIDE), w the simultaneity window (contact_tol,
 * or for the adaptive methods 100 (atol + rtol l) if larger; l the largest |point coordinate|): the depth at
 * which the loop itself reports a lost contact.  A start on or inside the walls is accepted, and so is a state
 * the loop itself left (its resting contacts held at their landing gaps).  On any of these errors *sim, dwork
 * and iwork are left unchanged; sim must have been initialised with GAC_OK before it is passed to
 * gac_sim_advance.
 * Returns GAC_OK or an error (< 0). */
int gac_sim_init(gac_sim *sim, const gac_model *m, double *dwork, int *iwork, double t0, const double *q,
                 const double *qd, const double *p, const gac_options *opt);

/* Set the inputs u (nu values, copied) held from now on: the next gac_sim_advance integrates with them.  The
 * flight derivative is re-evaluated and resting contacts that the new inputs pull off their walls are
 * released at the start of the next advance (GAC_SIM_CONTACT).  Returns GAC_OK, GAC_ERR_NULL_ARGUMENT (sim
 * NULL, or u NULL with nu > 0) or GAC_ERR_BAD_INPUT (a value not finite; nothing changed). */
int gac_sim_set_input(gac_sim *sim, const double *u);

/* Let controller(t, q, qd, u, user) give the inputs from now on (NULL: back to the held inputs).  Its output
 * must be finite (GAC_ERR_BAD_INPUT otherwise, at the next call that evaluates it).  Returns GAC_OK or
 * GAC_ERR_NULL_ARGUMENT (sim NULL). */
int gac_sim_set_controller(gac_sim *sim, gac_controller controller, void *user);

/* Give the controller set by gac_sim_set_controller its Jacobian jacobian(t, q, qd, du_dq, du_dqd, user) (the same
 * user pointer; NULL: none), so that the sensitivities (gac_sens_attach) follow its feedback: wherever they take the
 * flight's tangent, the inputs' direction is du_j = du_dq dq_j + du_dqd dqd_j (in chart A's coordinates, dq_j and
 * dqd_j carried there on chart B); at a release or a slip, whose event rates take u's derivative along the flow, its
 * explicit time derivative is the central difference of the controller at the fixed state (0 exactly for a controller
 * of the state alone).  Without it a controller ends the sensitivities (GAC_SENS_CONTROLLER).  A later
 * gac_sim_set_controller or gac_sim_set_schedule drops it.  Returns GAC_OK, GAC_ERR_NULL_ARGUMENT (sim NULL) or
 * GAC_ERR_BAD_OPTION (a Jacobian without a controller, or with a schedule's; nothing changed). */
int gac_sim_set_controller_jacobian(gac_sim *sim, gac_controller_jacobian jacobian);

/* The clock the wall-time budget (opt.max_wall_time) is measured with (NULL: C's clock(), the process's processor
 * time); the budget starts again from now.  Returns GAC_OK or GAC_ERR_NULL_ARGUMENT (sim NULL). */
int gac_sim_set_clock(gac_sim *sim, gac_clock clock, void *user);

/* Call progress(sim, user) every GAC_LOOK_STEPS steps and at the start of every gac_sim_advance (NULL: none); a
 * nonzero return stops the run with GAC_ERR_STOPPED.  Returns GAC_OK or GAC_ERR_NULL_ARGUMENT (sim NULL). */
int gac_sim_set_progress(gac_sim *sim, gac_progress progress, void *user);

/* A gac_controller giving the schedule's value at t (user: a const gac_schedule *).  With gac_sim_set_controller
 * the loop does not know the schedule's breakpoints; gac_sim_set_schedule is the exact way to drive a run by it. */
void gac_schedule_input(double t, const double *q, const double *qd, double *u, void *schedule);

/* Drive the run by the schedule s (checked by gac_schedule_check; the caller keeps it alive) from now on: every
 * gac_sim_advance ends a step at each of the schedule's breakpoints, so that a jump (held) or a kink (linear) falls on a
 * step boundary, and starts the next step from a fresh derivative with the resting contacts re-checked; a held
 * schedule's value is held over each interval [t_k, t_k+1) (gac_sim_set_input at t_k), a linear one is evaluated
 * at every stage.  s NULL: no schedule (the inputs stay as they are).  A later gac_sim_set_controller replaces it.
 * Returns GAC_OK, GAC_ERR_NULL_ARGUMENT (sim NULL), or the error of gac_schedule_check (nothing changed). */
int gac_sim_set_schedule(gac_sim *sim, const gac_schedule *s);

/* GAC_OK if the schedule is usable: pointers set, n >= 1, breakpoints finite and strictly increasing
 * (GAC_ERR_BAD_OPTION), values finite (GAC_ERR_BAD_INPUT). */
int gac_schedule_check(const gac_schedule *s);

/* Bind sim to model m and point its arrays at dwork / iwork (laid out as gac_sim_init does), e.g. after the
 * struct and its arrays were copied elsewhere.  Changes nothing else (the arrays' contents stay). */
void gac_sim_bind(gac_sim *sim, const gac_model *m, double *dwork, int *iwork);

/* Point the arrays of record at dwork (gac_record_ndouble(m) doubles) and iwork (gac_record_nint(m) ints). */
void gac_record_bind(gac_impact_record *record, const gac_model *m, double *dwork, int *iwork);

/* The current time and state, in chart A's coordinates (sim->x converted when the loop is on chart B: sim->x
 * is the state of the chart integrated now, sim->chart).  sim NULL: nothing is written; an output that is
 * NULL (t, q or qd) is skipped. */
void gac_sim_state(const gac_sim *sim, double *t, double *q, double *qd);

/* Integrate until t_end, the first impact (which is located, resolved and applied; record filled) or the
 * first release of a resting contact.
 * Samples: for each t_eval[i] (ascending) with i >= *i_eval that is passed, x_eval[i*nx ..] receives the
 * state [q, qd] (pre-impact at an impact time) and *i_eval advances.
 * Pointers: sim and record (bound) must not be NULL, nor t_eval, i_eval and x_eval (n_eval doubles,
 * n_eval nx doubles) when n_eval > 0 (GAC_ERR_NULL_ARGUMENT); with n_eval = 0 they may be NULL and are
 * not used.  Ranges (GAC_ERR_BAD_OPTION): t_end finite and >= sim->t, n_eval >= 0, 0 <= *i_eval <= n_eval.
 * A call refused for its arguments changes nothing.
 * Returns GAC_SIM_END, GAC_SIM_IMPACT, GAC_SIM_CONTACT or an error (< 0). */
int gac_sim_advance(gac_sim *sim, double t_end, const double *t_eval, int n_eval, int *i_eval,
                    double *x_eval, gac_impact_record *record);

/* What gac_sim_run reports of a whole run. */
typedef struct {
    long n_impacts;              /* impacts applied */
    double t_first_impact;       /* s; -1 when there was none */
    double loss_impacts;         /* J: sum of (energy_before - energy_after) over the impacts */
    long n_contact_events;       /* GAC_SIM_CONTACT ends (contacts come to rest, released, stuck or slipping) */
} gac_run_summary;

/* Run to t_end in one call: gac_sim_advance until GAC_SIM_END or an error (GAC_ERR_MAX_IMPACTS once
 * opt.max_impacts impacts were applied), counting into summary (zeroed first).  For studies of many runs: the whole run
 * stays in C.  record: a bound record (not NULL), overwritten at each impact.  Returns GAC_SIM_END or an error (< 0). */
int gac_sim_run(gac_sim *sim, double t_end, gac_impact_record *record, gac_run_summary *summary);

/* ---- forward sensitivities of a run (gac_sens.c) ---------------------------------------------------- */

/* Forward sensitivities S(t) = d x(t) / d(direction) of a hybrid run along k directions, each a seed of the
 * initial state dx0 (nx) and of the parameters dp (nparam).  In flight S solves the variational equations
 *     S' = (df/dx) S + (df/dp) dp,      column j: [dqd_j ; forward_dynamics_tangent(q, qd, u, p, dq_j, dqd_j, du_j, dp_j)]
 * integrated by the run's own Runge-Kutta formula (RK4, DOPRI5's or DOP853's weights) over the very steps the state
 * takes, the stages taken from the step itself (the directions GAC_TANGENT_BLOCK at a time through
 * forward_dynamics_tangent_block where the model has it); S is not in the step's error norm (the state's error
 * control alone chooses the steps).  du_j = 0 for held inputs and schedules (functions of t alone), and for a
 * controller with its Jacobian (gac_sim_set_controller_jacobian) du_j = du_dq dq_j + du_dqd dqd_j, at the stages, in
 * the resting contacts' constrained flight and at the events alike (the fields f- and f+ below hold the
 * controller's u).  At an impact of the frictionless law at time t*, located by contact c's gap:
 *     dt*_j = -(dg_j) / (w_c . qd-),  dg_j = contact_gaps_tangent(q, p, dq_j, dp_j)[c],  w_c = J^T (sign e_row_c)
 *     S+_j = D Delta (S-_j + f- dt*_j, dp_j) - f+ dt*_j
 * (the saltation matrix of Hiskens & Pai 2000, with the parameters' direct part), Delta the impact map of the
 * contacts that took an impulse (walls and joint stops alike), their set held fixed: A F = -(1 + E) W qd,
 * qd+ = qd + Y F, W their signed rows, Y = I_f^-1 W^T, A = W Y; differentiated by inertia_solve_tangent and
 * contact_generalized_force_tangent (e = p[e_index] is a parameter like any other; a landing is struck with e = 0);
 * a link pair or an obstacle struck alone: Newton's law on its row J^T n, differentiated by
 * gac_contact_normal_tangent.  A contact of the impact with impulse ~0 that leaves at the law's bound
 * (xi_b = w_b . qd+ + e_b w_b . qd- ~ 0) is a mode boundary: with sens.one_sided each column j takes the set its own
 * direction leads to, the law's complementarity differentiated: with b pushing, dF_b >= 0; without, dxi_b >= 0
 * (exactly one holds for a generic direction: dF_b = -dxi_b(without) / s_b, s_b > 0 the Schur complement of A);
 * the column is then the derivative from that side (its direction's), sens.n_boundaries counts such impacts.
 * Resting contacts (walls, and link pairs and obstacles by their rows J^T n and frame rows J^T t1, J^T t2, whose
 * biases' change along q and p is a fourth-order central difference): in flight the constrained dynamics' tangent
 * (the forces' by contact_bias_tangent) and the derivative of the projection after each step; a landing's jump uses
 * the field with the set after held and the hold's projection; a release (its force lambda_c reaching 0) dt*_j =
 * -d lambda_c / lambda_c', S+ = S- + (f- - f+) dt*; contacts at rest at the start: their projection.  On rough walls,
 * links and obstacles: a stuck point's tangential rows held with its normal one; a sliding point's friction -c_f lambda phi in the flight's tangent
 * (lambda through the unsymmetric B, phi = v_t / max(|v_t|, v_s) and c_f differentiated, and the slip direction's
 * derivative over two tangential axes, sens.dslip); a slip at its event lambda_N = |lambda_T| / c_f by that event's
 * time, S+ = S- + (f- - f+) dt*; sticking at a
 * step's end as the event |v_t| = v_s, S+ = D P (S- + f- dt*) - f+ dt*, P the velocities' projection onto the stuck
 * rows.  A switch of base chart
 * (x_B = phi(x_A), either way): S_B = (d phi / dx_A) S_A (gac_chart_convert_tangent), with no saltation term, as
 * the two charts' fields are phi-related; S is carried in the coordinates of the chart integrated now and reported
 * in chart A's (gac_sens_state, the samples).  Events this does not differentiate end the sensitivities (status
 * below): S and dt_impact are then NaN from that event on, the run itself continues.  The status codes: */
#define GAC_SENS_VALID         0   /* every event so far differentiated */
#define GAC_SENS_RESTING       1   /* a point sliding at rest on a rough wall, link or obstacle where its friction is
                                      not followed: with
                                      a slip direction over two tangential axes whose derivative is not known (given
                                      by a stick test at a step's end where other points stuck, or not the direction
                                      the stuck solve gives), or slower than friction_velocity at an impact */
#define GAC_SENS_FRICTION      2   /* an impact by a frictional law other than GAC_IMPACT_LAW_GDI solved with each
                                      contact's own e (a round with a common e, Newton + Coulomb): the GDI law's
                                      stuck and sliding contacts are differentiated */
#define GAC_SENS_STOP          3   /* (not raised since joint stops are differentiated; the code stays reserved) */
#define GAC_SENS_SIMULTANEOUS  4   /* an impact whose active contacts' rows are dependent (in one of its rounds), one
                                      that applied no impulse, or one of several rounds whose rounds the
                                      sensitivities could not reproduce from its record (or too many to trace:
                                      gac_sens.c); the rounds of the frictionless and GDI laws are differentiated,
                                      as the chain of the rounds' laws */
#define GAC_SENS_GRAZING       5   /* a contact met its wall with normal velocity ~ 0 (|w . qd-| below 1e-9 of the
                                      chain's speed scale), or touched it without an impact: t* not differentiable */
#define GAC_SENS_TANGENTIAL    6   /* a tangential impact (record.law GAC_IMPACT_LAW_GDI_TANGENTIAL) */
#define GAC_SENS_CHART         7   /* the loop switched to (or started on) a base chart without tangent kernels
                                      (a model built before chart B had them), or at that chart's own lock */
#define GAC_SENS_CONTROLLER    8   /* a controller gives the inputs (they may depend on the state; du = 0 is assumed
                                      only for held inputs and schedules) and has no Jacobian
                                      (gac_sim_set_controller_jacobian), or a linear schedule's inputs vary over a
                                      release or a slip */
#define GAC_SENS_NONFINITE     9   /* the sensitivities overflowed (not finite) */
#define GAC_SENS_BOUNDARY     10   /* a mode boundary: inside an impact of several contacts, a contact took an impulse
                                      ~0 and leaves at the law's bound (w . qd+ + e w . qd- ~ 0), so a perturbation
                                      may add it to the active set or drop it (with sens.one_sided = 1 each column
                                      takes its own side instead, where the law is frictionless on those contacts
                                      and none slides: n_boundaries counts them); in an impact of several rounds a
                                      contact at its bound in one of them (impulse ~0 and leaving at that round's
                                      bound, meeting a round at rest without being held there, left at rest by the
                                      last round, or on the cone with xi_T ~ 0), one-sided or not; or resting
                                      contacts released together
                                      (their forces ~0 at once), a slip with another slip or a release, or points
                                      that stick at one step's end at different speeds */
#define GAC_SENS_LINK         11   /* two links or a link on a fixed obstacle (GAC_CONTACT_LINK,
                                      GAC_CONTACT_OBSTACLE) where their closest points or frame have no derivative
                                      (crossing or parallel axes, a link parallel to a box's or plane's face); one
                                      struck, alone or with other contacts, by Newton's law or the frictional law,
                                      in one round or several, and one held at rest, smooth, stuck or sliding (its rows
                                      J^T n and, rough, J^T t1, J^T t2, their biases and derivatives:
                                      gac_rowless_bias_tangent, gac_contact_frame_tangent), its slips and sticking
                                      among them, are differentiated */
#define GAC_SENS_STICK        12   /* a stick-slip transition on a rough wall not differentiated: a stuck point that
                                      left the wall (its force reaching 0 while stuck), a stuck point that slipped
                                      at an impact, or one that came to stick at an impact without taking its
                                      impulse */

/* The sensitivities of one run: pointers into the caller's dwork (gac_sens_ndouble(m, k) doubles), laid out as
 * S (k nx) | dp (k nparam) | dt_impact (k) | dgap_held (k max(ncontact, 1)) | dslip (2 k max(ncontact, 1)) |
 * slip_known (2 max(ncontact, 1)) | scratch | S_keep (k nx).  Direction-major: S[j*nx + i] = d x_i / d direction j
 * (x = [q, qd] at sim.t in the coordinates of the chart integrated now, sim.chart: gac_sens_state gives chart A's),
 * dp[j*nparam + i] the parameter seed of direction j. */
typedef struct gac_sens_s {
    int k;                       /* directions */
    double *S;                   /* k x nx: the sensitivities at sim.t, on the chart integrated now (NaN once
                                    status is not GAC_SENS_VALID) */
    double *dp;                  /* k x nparam: the parameter seeds (constant) */
    double *dt_impact;           /* k: d t* / d direction j of the last event differentiated: an impact (a landing
                                    among them), or a release (s per unit) */
    int status;                  /* GAC_SENS_VALID or the first event not differentiated (GAC_SENS_*) */
    double t_status;             /* s: the time of that event */
    int contact_status;          /* its contact (0..ncontact-1), -1: none */
    long n_impacts;              /* impacts differentiated */
    double *dgap_held;           /* k x max(ncontact, 1): d(the gap a resting contact is held at) / d direction j */
    double *dslip;               /* k x 2 max(ncontact, 1): d(a sliding point's slip direction, sim.slip) / d direction
                                    j, known where it was set by a slip over two tangential axes */
    double *slip_known;          /* 2 max(ncontact, 1): the slip directions dslip is of (a point whose sim.slip
                                    differs, over two axes, was given its direction elsewhere: not followed) */
    double *work;                /* scratch: the stages */
    double *S_keep;              /* scratch: S kept while a sample's is formed (k x nx) */
    double *S_eval;              /* NULL (default), or the caller's n_eval x k x nx: S at each sample the loop writes
                                    to x_eval (the same index), formed by the run's Runge-Kutta formula from the
                                    step's start to the sample (one step of the directions' stages per sample),
                                    in chart A's coordinates like the samples; NaN from the first event not
                                    differentiated on (and at a sample at chart A's lock).  Set after
                                    gac_sens_attach. */
    int one_sided;               /* 0 (default): a mode boundary inside an impact ends the sensitivities
                                    (GAC_SENS_BOUNDARY); 1: each column there takes the mode its own direction leads
                                    to (below), so a column is the derivative along its direction from that side
                                    only: seed +e_j and -e_j to have the right and the left derivative.  Set after
                                    gac_sens_attach. */
    long n_boundaries;           /* mode boundaries inside impacts crossed so (one_sided = 1): 0, or the columns
                                    are one-sided derivatives from the first on */
    double t_boundary;           /* s: the time of the first one */
    int contact_boundary;        /* its contact (0..ncontact-1, the one at the law's bound), -1: none */
} gac_sens;

/* Doubles of a gac_sens's dwork: S, dp, dt_impact, the held gaps' derivatives, the slip directions' derivatives and
 * the directions they are of, 12 stage derivatives of the state and of each direction, and S kept while a sample's
 * is formed. */
#define GAC_SENS_NDOUBLE(nq, nparam, ncontact, k) \
    (14L * (k) * 2 * (nq) + (long)(k) * (nparam) + (k) + (3L * (k) + 2) * ((ncontact) > 0 ? (ncontact) : 1) \
     + 14L * 2 * (nq))
long gac_sens_ndouble(const gac_model *m, int k);

/* Attach sensitivities along k directions to sim from its current time on: S = seed_x (k x nx, direction-major),
 * dp = seed_p (k x nparam; NULL: 0).  The loop then carries them (sim.sens); sens and dwork owned by the caller for
 * the life of the run.  sens NULL detaches.  Returns GAC_OK, GAC_ERR_NULL_ARGUMENT (sim, seed_x or dwork NULL),
 * GAC_ERR_BAD_OPTION (k < 1, a seed not finite, a seed_p along a box's rotation entries, or along a plane's normal
 * entries other than a turn, n . dn = 0: constrained; an obstacle's position and size are directions, and a plane's
 * normal turned about its point) or
 * GAC_ERR_BAD_MODEL (the model has no tangent kernels: rolled forward dynamics, or built with tangent=False). */
int gac_sens_attach(gac_sim *sim, gac_sens *sens, int k, const double *seed_x, const double *seed_p, double *dwork);

/* S (k x nx) at sim.t in chart A's coordinates, whichever chart is integrated (as gac_sim_state gives the state):
 * sens.S itself, or on chart B its conversion (gac_chart_convert_tangent; NaN at chart A's lock).  GAC_OK or
 * GAC_ERR_NULL_ARGUMENT (sim, S NULL, or no sensitivities attached). */
int gac_sens_state(const gac_sim *sim, double *S);

#ifdef __cplusplus
}
#endif

#endif /* GAC_H */
