"""Projection-paper experiment (Giftthaler & Buchli, Sec. IV-C and Fig. 3): a 6-DoF arm whose end
effector follows a sinusoid while joint 1 turns by 90°.

Robot: UR5 from example-robot-data (6 DoF, fixed base) — the paper's hydraulic arm is not
available.  Dynamics: :class:`DifferentialActionModelFreeFwdDynamics` with full actuation, RK4
(relative degree one for a position constraint).  Task: joint 1 rotates by 90° (posture cost to
``q0 + [π/2, 0, …]``, small velocity and torque regularisation).  Constraint (every node, terminal
included): the tool stays on the sinusoidal band ``z = z₀ + A sin(4 (θ - θ₀))`` around the base's
vertical axis (``θ`` the tool's azimuth), which passes through the initial end-effector pose, so
turning joint 1 by 90° drives the tool over one period of the sinusoid (the paper's exact path is
not given).  Initial guess: gravity compensation at
``x0`` rolled out (the arm stays at rest), i.e. the inverse-dynamics feed-forward without the LQR.

:func:`run_projection_arm` prints the iteration table, the constraint ISE ``Σₜ Δt ‖hₜ‖²``, CPU time
and the time per iteration against ``N`` at fixed T with the least-squares line and its R².
Pinocchio and the models are imported inside the functions (the core stays numpy-only).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from .residual_base import ResidualDataAbstract, ResidualModelAbstract


class ResidualModelSinusoidPath(ResidualModelAbstract):
    """``h = p_z - z₀ - A sin(ω (atan2(p_y, p_x) - θ₀))`` for a frame position ``p`` (1 row).

    The frame must stay on a sinusoidal band around the base's vertical axis that passes through
    its initial position (azimuth ``θ₀``, height ``z₀``); ``frame`` is a residual whose ``r`` is the
    frame position (a frame-translation residual with zero reference).
    """

    def __init__(self, frame: ResidualModelAbstract, p0: np.ndarray, amplitude: float, omega: float) -> None:
        super().__init__(frame.state, 1, frame.nu, True, False, False)
        self.frame = frame
        self.z0 = float(p0[2])
        self.theta0 = float(np.arctan2(p0[1], p0[0]))
        self.amplitude = float(amplitude)
        self.omega = float(omega)

    def createData(self, data=None) -> ResidualDataAbstract:
        rdata = ResidualDataAbstract(self, data)
        rdata.frame = self.frame.createData(data)
        return rdata

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        self.frame.calc(data.frame, x, u)
        px, py, pz = data.frame.r
        phase = self.omega * (np.arctan2(py, px) - self.theta0)
        data.r[0] = pz - self.z0 - self.amplitude * np.sin(phase)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        self.frame.calcDiff(data.frame, x, u)
        px, py, _ = data.frame.r
        rho2 = px * px + py * py
        c = self.amplitude * self.omega * np.cos(self.omega * (np.arctan2(py, px) - self.theta0))
        dh_dp = np.array([c * py / rho2, -c * px / rho2, 1.0])
        data.Rx[0] = dh_dp @ data.frame.Rx


def build_arm_problem(
    dt: float = 5e-3, horizon: float = 3.0, amplitude: float = 0.05, integrator: str = "rk4", posture_weight=1e-2
):
    """The arm problem; returns ``(problem, us0, info)`` with the gravity-compensation guess ``us0``.

    Parameters
    ----------
    dt, horizon : float
        Time step and horizon (``N = round(horizon / dt)`` nodes).
    amplitude : float
        Amplitude of the height sinusoid (m); one period over the 90° sweep of joint 1.
    integrator : {"rk4", "euler"}
        Time discretisation.
    posture_weight : float
        Weight of the running posture cost (the terminal one is 100).
    """
    import example_robot_data
    import pinocchio as pin

    from . import (
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
    from .models import (
        ActuationModelFull,
        DifferentialActionModelFreeFwdDynamics,
        ResidualModelFrameTranslation,
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
    N = int(round(horizon / dt))
    ugrav = pin.rnea(model, data, q0, np.zeros(model.nv), np.zeros(model.nv))
    wstate = np.r_[np.ones(model.nv), 0.1 * np.ones(model.nv)]
    path = ResidualModelSinusoidPath(ResidualModelFrameTranslation(state, fid, np.zeros(3), nu), p0, amplitude, 4.0)
    dams = []
    for terminal in (False, True):
        costs = CostModelSum(state, nu)
        posture = ResidualModelState(state, xT, nu)
        costs.addCost("posture", CostModelResidual(state, ActivationModelWeightedQuad(wstate), posture),
                      100.0 if terminal else posture_weight)
        if not terminal:
            costs.addCost("effort", CostModelResidual(state, ResidualModelControl(state, ugrav)), 1e-3)
        constraints = ConstraintModelManager(state, nu)
        constraints.addConstraint("ee_path", ConstraintModelResidual(state, path))
        dams.append(DifferentialActionModelFreeFwdDynamics(state, actuation, costs, constraints))
    if integrator == "rk4":
        running, terminal_model = (IntegratedActionModelRK(d, RKType.four, h) for d, h in zip(dams, (dt, 0.0)))
    else:
        running, terminal_model = (IntegratedActionModelEuler(d, h) for d, h in zip(dams, (dt, 0.0)))
    models = [running] * N + [terminal_model]
    problem = ShootingProblem(x0, models[:-1], models[-1])
    us0 = [ugrav.copy() for _ in range(N)]
    return problem, us0, {"N": N, "dt": dt, "robot": "ur5", "frame": "tool0", "p0": p0}


def constraint_ise(problem, dt: float) -> float:
    """``Σₜ Δt ‖hₜ‖²`` over the running nodes plus ``‖h_T‖² Δt`` (after ``problem.calc``)."""
    total = sum(float(d.h[: m.nh] @ d.h[: m.nh]) for m, d in zip(problem.runningModels, problem.runningDatas))
    hT = problem.terminalData.h[: problem.terminalModel.nh_T]
    return dt * (total + float(hT @ hT))


def run_projection_arm(
    dt: float = 5e-3,
    horizon: float = 3.0,
    maxiter: int = 20,
    timing_N: Sequence[int] = (150, 300, 600, 1200),
    timing_iters: int = 5,
    th_stop: float = 1e-6,
    verbose: bool = True,
) -> dict:
    """Run the arm experiment and the time-per-iteration scaling; print the paper-style report.

    Parameters
    ----------
    dt, horizon : float
        Main run (paper: 5 ms, 3 s, N = 600).
    maxiter : int
        Iteration limit of the main run (bar: converge within 20).
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
        ``converged, iterations, cost, ise, hfeas, cpu_s, timing`` (list of ``(N, s/iter)``), ``r2``.
    """
    from . import SolverProjection

    def say(msg: str) -> None:
        if verbose:
            print(msg, flush=True)

    problem, us0, info = build_arm_problem(dt, horizon)
    solver = SolverProjection(problem)
    solver.th_stop = th_stop
    rows = []
    solver.setCallbacks([lambda s: rows.append((s.iter, s.cost, s.hfeas, s.stepLength, s.stop))])
    xs0 = problem.rollout(us0)
    say(f"Projection solver — {info['robot']} (6 DoF), tool on a sinusoidal path, T = {horizon:g} s, "
        f"dt = {dt * 1e3:g} ms, RK4, N = {info['N']}")
    t0 = time.perf_counter()
    ok = solver.solve(xs0, us0, maxiter=maxiter, is_feasible=True)
    cpu = time.perf_counter() - t0
    problem.calc(solver.xs, solver.us)
    ise = constraint_ise(problem, dt)
    say(f"{'iter':>4} {'cost':>12} {'hfeas(inf)':>11} {'step':>7} {'stop':>10}")
    for it, cost, hfeas, step, stop in rows:
        say(f"{it:4d} {cost:12.6g} {hfeas:11.3e} {step:7.4f} {stop:10.3e}")
    iters = solver.iter + (1 if ok else 0)
    say(f"converged: {ok} ({solver.reason}) after {iters} iterations; cost {solver.cost:.6g}; "
        f"constraint ISE {ise:.3e} (paper: 10 iterations, ISE 0.0013); CPU {cpu:.2f} s "
        f"({1e3 * cpu / max(iters, 1):.0f} ms/iteration)")
    out = {"converged": ok, "iterations": iters, "cost": solver.cost, "ise": ise, "hfeas": solver.hfeas,
           "cpu_s": cpu, "timing": [], "r2": float("nan")}
    if timing_N:
        say(f"Time per iteration vs N (T = {horizon:g} s fixed; one iteration's work = calc + calcDiff + "
            f"projected backward pass + one rollout (step 0), best of {timing_iters}):")
        for N in timing_N:
            p, us, _ = build_arm_problem(horizon / N, horizon)
            s = SolverProjection(p)
            xs = p.rollout(us)
            s.setCandidate(xs, us, True)
            samples = []
            for _ in range(timing_iters + 1):
                t0 = time.perf_counter()
                p.calc(xs, us)
                s.computeDirection(True)
                s.tryStep(0.0)
                samples.append(time.perf_counter() - t0)
            per = float(np.min(samples[1:]))
            out["timing"].append((N, per))
            say(f"  N = {N:5d}: {1e3 * per:9.1f} ms/iteration")
        Ns = np.array([n for n, _ in out["timing"]], dtype=float)
        ts = np.array([t for _, t in out["timing"]])
        slope, intercept = np.polyfit(Ns, ts, 1)
        pred = slope * Ns + intercept
        ss_tot = float(np.sum((ts - ts.mean()) ** 2))
        out["r2"] = 1.0 - float(np.sum((ts - pred) ** 2)) / ss_tot if ss_tot > 0 else 1.0
        say(f"  linear fit: {1e6 * slope:.1f} µs per node + {1e3 * intercept:.1f} ms, R² = {out['r2']:.4f}")
    return out
