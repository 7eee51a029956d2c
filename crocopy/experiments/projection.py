"""Projection-paper experiment (Giftthaler & Buchli, Sec. IV-C and Fig. 3): a 6-DoF arm whose end
effector is constrained to a sinusoid while joint 1 turns by 90°.

Robot: UR5 from example-robot-data (6 DoF, fixed base) — the paper's hydraulic arm is not
available.  Dynamics: :class:`DifferentialActionModelFreeFwdDynamics`, full actuation, Δt = 5 ms,
T = 3 s.  Task: joint 1 rotates by 90° (posture cost to ``q0 + [π/2, 0, …]``, small velocity and
torque regularisation).  Path (the paper's is not given): the tool stays on the vertical cylinder
through its initial position (radius ``ρ₀`` around the base axis) at the height
``z_ref(t) = z₀ + ½ A (1 - cos 2πt/T)``, ``A = 20 cm``; turning joint 1 sweeps it along one period
of a sinusoid on that cylinder.  Path error ``e = [ρ - ρ₀, z - z_ref]``, 2 rows on every node
(terminal included), one model per node.  The path starts at the initial pose with zero velocity,
so ``x0`` satisfies it (the method requires it).  Initial guess: gravity compensation at ``x0``
rolled out (the paper's inverse-dynamics feed-forward; the arm stays at rest), which violates
the path by up to 20 cm (path ISE 0.045 m²s): the solver has to remove the violation.

Discretisation (measured by :func:`policy_check`): with RK4 (the paper's integrator) and the
position rows ``e = 0``, the one-step preview of a second-order system leaves two closed-loop
eigenvalues of the projected policy at ``-1`` (sampling zeros): marginally stable chatter that
the nonlinear rollout from the rest guess excites until it diverges, so only tiny steps are
accepted.  The RK4 run therefore constrains ``e + τ ė = 0`` (τ = 50 ms), which with
``e(0) = ė(0) = 0`` keeps ``e ≡ 0`` and moves those eigenvalues inside the unit circle.
crocopy's Euler step is semi-implicit (``q' = q ⊕ (v + a Δt) Δt``): position rows already have
relative degree one and no zero at ``-1``, so a second run uses Euler with the plain rows ``e = 0``.

:func:`run_projection_arm` prints both solves (iteration table with the equality feasibility,
path ISE ``∫ ‖e‖² dt ≈ Σₙ Δt ‖eₙ‖²`` from forward kinematics before and after, CPU time), the
policy check, and the time per iteration against ``N`` at fixed T with the least-squares line and
its R², each bar marked met/not met.  Pinocchio and the models are imported inside the functions
(the core stays numpy-only).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from ..residuals.base import ResidualDataAbstract, ResidualModelAbstract

BARS = {"iterations": 20, "ise": 1e-2, "r2": 0.98}


def _mark(ok: bool) -> str:
    return "met" if ok else "NOT MET"


class ResidualModelCylinderPath(ResidualModelAbstract):
    """Tool on a vertical cylinder at a given height, with an optional velocity term (2 rows).

    With ``e = [ρ - ρ₀, p_z - z_ref]`` (``ρ = √(p_x² + p_y²)`` the distance of the frame position
    ``p`` from the base axis) the residual is ``r = e + τ ė`` with ``ė = [ρ̇, ṗ_z - ż_ref]``.
    ``τ = 0`` is the plain position constraint; ``τ > 0`` keeps ``e ≡ 0`` whenever ``e = ė = 0`` at the
    start, and gives the constraint relative degree one in continuous time (see the module notes).
    ``position`` is a frame-translation residual with zero reference (``r = p``); ``velocity`` a
    LOCAL_WORLD_ALIGNED frame-velocity residual of the same frame with zero reference (its first
    three rows are ``ṗ``), required when ``tau > 0``.  A time-varying path uses one instance per node.
    """

    def __init__(
        self,
        position: ResidualModelAbstract,
        radius: float,
        height: float,
        velocity: ResidualModelAbstract | None = None,
        height_rate: float = 0.0,
        tau: float = 0.0,
    ) -> None:
        if tau < 0.0 or (tau > 0.0 and velocity is None):
            raise ValueError(f"tau must be >= 0 and needs a velocity residual when positive, got tau={tau}")
        super().__init__(position.state, 2, position.nu, True, tau > 0.0, False)
        self.position, self.velocity = position, velocity if tau > 0.0 else None
        self.radius, self.height = float(radius), float(height)
        self.height_rate, self.tau = float(height_rate), float(tau)

    def createData(self, data=None) -> ResidualDataAbstract:
        rdata = ResidualDataAbstract(self, data)
        rdata.position = self.position.createData(data)
        rdata.velocity = self.velocity.createData(data) if self.velocity is not None else None
        return rdata

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        self.position.calc(data.position, x, u)
        px, py, pz = data.position.r
        rho = np.hypot(px, py)
        data.r[0] = rho - self.radius
        data.r[1] = pz - self.height
        if self.velocity is not None:
            self.velocity.calc(data.velocity, x, u)
            vx, vy, vz = data.velocity.r[:3]
            data.r[0] += self.tau * (px * vx + py * vy) / rho
            data.r[1] += self.tau * (vz - self.height_rate)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        self.position.calcDiff(data.position, x, u)
        px, py, _ = data.position.r
        rho = np.hypot(px, py)
        P = data.position.Rx
        drho = (px * P[0] + py * P[1]) / rho
        data.Rx[0] = drho
        data.Rx[1] = P[2]
        if self.velocity is not None:
            self.velocity.calcDiff(data.velocity, x, u)
            vx, vy, _ = data.velocity.r[:3]
            V = data.velocity.Rx
            rho_dot = (px * vx + py * vy) / rho
            drho_dot = (vx * P[0] + vy * P[1] + px * V[0] + py * V[1]) / rho - rho_dot * drho / rho
            data.Rx[0] += self.tau * drho_dot
            data.Rx[1] += self.tau * V[2]

    def path_error(self, data: ResidualDataAbstract) -> np.ndarray:
        """The position error ``e = [ρ - ρ₀, p_z - z_ref]`` of the last :meth:`calc`."""
        px, py, pz = data.position.r
        return np.array([np.hypot(px, py) - self.radius, pz - self.height])


def build_arm_problem(
    dt: float = 5e-3,
    horizon: float = 3.0,
    amplitude: float = 0.2,
    integrator: str = "rk4",
    posture_weight: float = 1e-2,
    tau: float = 0.05,
):
    """The arm problem; returns ``(problem, us0, info)`` with the gravity-compensation guess ``us0``.

    Parameters
    ----------
    dt, horizon : float
        Time step and horizon (``N = round(horizon / dt)`` nodes).
    amplitude : float
        Peak-to-peak amplitude ``A`` (m) of the height path ``z₀ + ½ A (1 - cos(2π t / horizon))``.
    integrator : {"rk4", "euler"}
        Time discretisation.
    posture_weight : float
        Weight of the running posture cost (the terminal one is 100).
    tau : float
        Velocity term of the path rows ``e + τ ė = 0`` (s); 0 constrains the position only.
    """
    import example_robot_data
    import pinocchio as pin

    from .. import (
        ActivationModelWeightedQuad,
        ConstraintModelManager,
        ConstraintModelResidual,
        CostModelResidual,
        CostModelSum,
        IntegratedActionModelEuler,
        IntegratedActionModelRK,
        ResidualModelControl,
        ResidualModelState,
        RKType,
        ShootingProblem,
    )
    from ..models import (
        ActuationModelFull,
        DifferentialActionModelFreeFwdDynamics,
        ResidualModelFrameTranslation,
        ResidualModelFrameVelocity,
        StateMultibody,
    )

    if integrator not in ("rk4", "euler"):
        raise ValueError(f"integrator must be 'rk4' or 'euler', got {integrator!r}")
    model = example_robot_data.load("ur5").model
    state = StateMultibody(model)
    actuation = ActuationModelFull(state)
    nu = actuation.nu
    q0 = np.array([0.0, -1.2, 1.6, -1.9, -1.57, 0.0])
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    xT = x0.copy()
    xT[0] += np.pi / 2
    data = model.createData()
    fid = model.getFrameId("tool0")
    pin.framesForwardKinematics(model, data, q0)
    p0 = data.oMf[fid].translation.copy()
    radius = float(np.hypot(p0[0], p0[1]))
    N = int(round(horizon / dt))
    ugrav = pin.rnea(model, data, q0, np.zeros(model.nv), np.zeros(model.nv))
    wstate = np.r_[np.ones(model.nv), 0.1 * np.ones(model.nv)]
    position = ResidualModelFrameTranslation(state, fid, np.zeros(3), nu)
    velocity = ResidualModelFrameVelocity(state, fid, pin.Motion.Zero(), pin.LOCAL_WORLD_ALIGNED, nu)
    posture = CostModelResidual(state, ActivationModelWeightedQuad(wstate), ResidualModelState(state, xT, nu))
    effort = CostModelResidual(state, ResidualModelControl(state, ugrav))
    omega = 2.0 * np.pi / horizon
    times = np.arange(N + 1) * dt
    heights = p0[2] + 0.5 * amplitude * (1.0 - np.cos(omega * times))
    rates = 0.5 * amplitude * omega * np.sin(omega * times)
    models = []
    for n, (z, zdot) in enumerate(zip(heights, rates)):
        terminal = n == N
        costs = CostModelSum(state, nu)
        costs.addCost("posture", posture, 100.0 if terminal else posture_weight)
        if not terminal:
            costs.addCost("effort", effort, 1e-3)
        constraints = ConstraintModelManager(state, nu)
        path = ResidualModelCylinderPath(position, radius, z, velocity, zdot, tau)
        constraints.addConstraint("ee_path", ConstraintModelResidual(state, path))
        dam = DifferentialActionModelFreeFwdDynamics(state, actuation, costs, constraints)
        h = 0.0 if terminal else dt
        models.append(IntegratedActionModelRK(dam, RKType.four, h) if integrator == "rk4"
                      else IntegratedActionModelEuler(dam, h))
    problem = ShootingProblem(x0, models[:-1], models[-1])
    us0 = [ugrav.copy() for _ in range(N)]
    info = {"N": N, "dt": dt, "robot": "ur5", "model": model, "frame_id": fid, "p0": p0, "radius": radius,
            "heights": heights, "tau": tau}
    return problem, us0, info


def path_ise(xs: Sequence[np.ndarray], info: dict) -> float:
    """Constraint ISE of the path, ``∫ ‖e(t)‖² dt ≈ Σₙ Δt ‖eₙ‖²`` over all nodes, terminal included.

    ``eₙ = [ρ(qₙ) - ρ₀, p_z(qₙ) - z_ref(tₙ)]`` is the tool's distance from the path, computed by
    Pinocchio's forward kinematics from the states alone (``info`` from :func:`build_arm_problem`).
    """
    import pinocchio as pin

    model, fid = info["model"], info["frame_id"]
    data = model.createData()
    total = 0.0
    for x, z in zip(xs, info["heights"]):
        pin.framesForwardKinematics(model, data, x[: model.nq])
        p = data.oMf[fid].translation
        total += (np.hypot(p[0], p[1]) - info["radius"]) ** 2 + (p[2] - z) ** 2
    return info["dt"] * total


def policy_check(dt: float = 5e-3, horizon: float = 0.5, tau: float = 0.05) -> list[tuple[str, str]]:
    """One projected backward pass from the rest guess for three discretisations of the path rows.

    For RK4 with the position rows (``τ = 0``), crocopy's semi-implicit Euler with the position rows
    and RK4 with ``e + τ ė``, reports either the rank error the solver raised or the eigenvalues
    of the closed-loop linear policy ``A - B K`` at the middle node: one-step position constraints
    of a second-order system leave the sampling zeros at ``-1`` (marginally stable chatter that the
    nonlinear rollout excites), the velocity term moves them inside the unit circle.
    """
    from .. import SolverProjection
    from ..solvers.projection_lq import ConstraintRankError

    out = []
    for label, integrator, t in (("RK4, e = 0", "rk4", 0.0), ("Euler, e = 0", "euler", 0.0),
                                 (f"RK4, e + {tau:g} ė = 0", "rk4", tau)):
        problem, us0, info = build_arm_problem(dt, horizon, integrator=integrator, tau=t)
        solver = SolverProjection(problem)
        solver.setCandidate(problem.rollout(us0), us0, True)
        try:
            solver.computeDirection(True)
        except ConstraintRankError as exc:
            out.append((label, f"rejected: {exc.kind} at node {exc.node}"))
            continue
        n = info["N"] // 2
        d = problem.runningDatas[n]
        ev = np.linalg.eigvals(d.Fx - d.Fu @ solver.K[n])
        out.append((label, f"relative degree one; closed-loop eigenvalues at node {n}: most negative "
                           f"{ev.real.min():+.4f}, largest |λ| {np.abs(ev).max():.4f}"))
    return out


def _timing(horizon: float, tau: float, timing_N: Sequence[int], repeats: int, say) -> tuple[list, float]:
    """Best-of-``repeats`` time of one iteration's work per ``N``; returns ``(rows, R²)``.

    The horizons are timed round-robin (one sample of each per round, after a warm-up round), so
    that load from other processes affects all of them alike.
    """
    from .. import SolverProjection

    runs = []
    for N in timing_N:
        p, us, _ = build_arm_problem(horizon / N, horizon, tau=tau)
        s = SolverProjection(p)
        xs = p.rollout(us)
        s.setCandidate(xs, us, True)
        runs.append((p, s, xs, us, []))
    for _ in range(repeats + 1):
        for p, s, xs, us, samples in runs:
            t0 = time.perf_counter()
            p.calc(xs, us)
            s.computeDirection(True)
            s.tryStep(1.0)
            samples.append(time.perf_counter() - t0)
    rows = [(N, float(np.min(r[4][1:]))) for N, r in zip(timing_N, runs)]
    for N, per in rows:
        say(f"  N = {N:5d}: {1e3 * per:9.1f} ms/iteration ({1e6 * per / N:.0f} µs/node)")
    Ns = np.array([n for n, _ in rows], dtype=float)
    ts = np.array([t for _, t in rows])
    slope, intercept = np.polyfit(Ns, ts, 1)
    ss_tot = float(np.sum((ts - ts.mean()) ** 2))
    r2 = 1.0 - float(np.sum((ts - slope * Ns - intercept) ** 2)) / ss_tot if ss_tot > 0 else 1.0
    say(f"  linear fit: {1e6 * slope:.1f} µs per node + {1e3 * intercept:.1f} ms, R² = {r2:.4f} "
        f"(bar ≥ {BARS['r2']}: {_mark(r2 >= BARS['r2'])})")
    return rows, r2


def solve_arm(
    dt: float = 5e-3,
    horizon: float = 3.0,
    integrator: str = "rk4",
    tau: float = 0.05,
    maxiter: int = 20,
    th_stop: float = 1e-6,
    say=print,
) -> dict:
    """Solve the arm problem from the gravity-compensation guess; print its table and bar marks.

    Returns
    -------
    dict
        ``converged, iterations, cost, ise0, ise, hfeas, cpu_s, bars`` (bar name -> met).
    """
    from .. import CallbackLogger, SolverProjection

    problem, us0, info = build_arm_problem(dt, horizon, integrator=integrator, tau=tau)
    solver = SolverProjection(problem)
    solver.th_stop = th_stop
    logger = CallbackLogger()
    solver.setCallbacks([logger])
    xs0 = problem.rollout(us0)
    ise0 = path_ise(xs0, info)
    problem.calc(xs0, us0)
    hfeas0 = max(float(np.max(np.abs(d.h), initial=0.0)) for d in [*problem.runningDatas, problem.terminalData])
    rows = "e + τ ė = 0" if tau else "e = 0"
    say(f"-- {integrator.upper()}, path rows {rows}{f' (τ = {tau:g} s)' if tau else ''}: initial guess max |h| "
        f"{hfeas0:.3e}, path ISE {ise0:.3e} m²s")
    t0 = time.perf_counter()
    ok = solver.solve(xs0, us0, maxiter=maxiter, is_feasible=True)
    cpu = time.perf_counter() - t0
    ise = path_ise(solver.xs, info)
    say(f"{'iter':>4} {'cost':>12} {'||hfeas||':>11} {'step':>7} {'stop':>10}")
    for it, cost, hfeas, step, stop in zip(logger.iters, logger.costs, logger.hfeass, logger.steps, logger.stops):
        say(f"{it:4d} {cost:12.6g} {hfeas:11.3e} {step:7.4f} {stop:10.3e}")
    iters = solver.iter + (1 if ok else 0)
    bars = {"iterations": ok and iters <= BARS["iterations"], "ise": ise <= BARS["ise"]}
    say(f"   converged: {ok} ({solver.reason}) after {iters} iterations (bar ≤ {BARS['iterations']}: "
        f"{_mark(bars['iterations'])}; paper 10)")
    say(f"   path ISE ∫‖e‖²dt {ise0:.3e} -> {ise:.3e} m²s (bar ≤ {BARS['ise']:g}: {_mark(bars['ise'])}; paper 0.0013); "
        f"max |h| {solver.hfeas:.3e}; cost {solver.cost:.6g}; CPU {cpu:.2f} s ({1e3 * cpu / max(iters, 1):.0f} "
        "ms/iteration; paper 0.70 s in C++)")
    return {"converged": ok, "iterations": iters, "cost": solver.cost, "ise0": ise0, "ise": ise,
            "hfeas": solver.hfeas, "cpu_s": cpu, "bars": bars}


def run_projection_arm(
    dt: float = 5e-3,
    horizon: float = 3.0,
    tau: float = 0.05,
    maxiter: int = 20,
    timing_N: Sequence[int] = (150, 300, 600, 1200),
    timing_iters: int = 5,
    th_stop: float = 1e-6,
    verbose: bool = True,
) -> dict:
    """Run the arm experiment and the time-per-iteration scaling; print the paper-style report.

    Two solves from the same rest guess: RK4 (the paper's integrator) with the rows ``e + τ ė = 0``,
    and crocopy's semi-implicit Euler with the plain position rows ``e = 0``; then
    :func:`policy_check` and the timing fit (RK4 configuration).

    Parameters
    ----------
    dt, horizon : float
        Main runs (paper: 5 ms, 3 s, N = 600).
    tau : float
        Velocity term of the RK4 run's path rows (s).
    maxiter : int
        Iteration limit of each solve (bar: converge within 20).
    timing_N : sequence of int
        Horizons (numbers of nodes at fixed ``horizon``) for the scaling fit; empty to skip.
    timing_iters : int
        Timed repetitions of one iteration's work per ``N`` (the minimum is reported, after a
        warm-up, to filter out load from other processes).
    th_stop : float
        Stopping threshold of the solver (``stop = |Δcost model| + σ Σ‖h‖₁``).
    verbose : bool
        Print the report.

    Returns
    -------
    dict
        ``rk4`` and ``euler`` (see :func:`solve_arm`), ``policy_check``, ``timing`` (list of
        ``(N, s/iter)``) and ``r2``.
    """

    def say(msg: str) -> None:
        if verbose:
            print(msg, flush=True)

    say(f"Projection solver — UR5 (6 DoF), T = {horizon:g} s, dt = {dt * 1e3:g} ms, N = {int(round(horizon / dt))}: "
        "joint 1 turns 90° while the tool stays on its cylinder around the base axis at the height "
        "z₀ + 20 cm · ½(1 - cos 2πt/T) (e = [ρ - ρ₀, z - z_ref], 2 rows on every node)")
    out = {"rk4": solve_arm(dt, horizon, "rk4", tau, maxiter, th_stop, say),
           "euler": solve_arm(dt, horizon, "euler", 0.0, maxiter, th_stop, say)}
    out["policy_check"] = policy_check(dt, tau=tau)
    for label, text in out["policy_check"]:
        say(f"policy of the path rows ({label}): {text}")
    out["timing"], out["r2"] = [], float("nan")
    if timing_N:
        say(f"Time per iteration vs N (RK4, τ = {tau:g} s, T = {horizon:g} s fixed; one iteration's work = calc + "
            f"calcDiff + projected backward pass + one full-step rollout, best of {timing_iters}):")
        out["timing"], out["r2"] = _timing(horizon, tau, timing_N, timing_iters, say)
    return out
