"""The cases of the census (``census.py``): for each public constructor, setter and call of the core and
multibody models, the call with good arguments (a check of the census itself) and with each bad value of
each argument, and valid but extreme points."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from census import (
    BOOLS,
    COUNTS,
    FRAME_TYPES,
    FRAMES,
    KEYS,
    NEGATIVE,
    NUMBERS,
    Case,
    bad_placements,
    bad_rotations,
    bad_spatial,
    bad_vectors,
    mb_point,
    mb_state,
    pinocchio_collector,
    sizeless,
)


def _cases_of(target: str, build: Callable[..., Any], good: dict[str, Any],
              bad: dict[str, list[tuple[str, Any]]]) -> Iterator[Case]:
    """The call with ``good`` arguments (must be ``ok``: a check of the census itself), then with each
    bad value of ``bad`` in place of its argument."""
    yield target, "-", "good", (lambda: build(**good)), True, None
    for arg, values in bad.items():
        for label, value in values:
            yield target, arg, label, (lambda a=arg, v=value: build(**{**good, a: v})), False, value


def _extreme(target: str, call: Callable[[Any], Any], size: int, arg: str) -> Iterator[Case]:
    for label, scale in (("+1e300", 1e300), ("-1e300", -1e300), ("1e160", 1e160)):
        yield target, arg, label, (lambda s=scale: call(np.full(size, s))), True, scale


def core_cases() -> Iterator[Case]:
    import crocopy as c

    sv = c.StateVector(4)
    acts = {
        "ActivationModelQuad": lambda n: c.ActivationModelQuad(n),
        "ActivationModelWeightedQuad": lambda n: c.ActivationModelWeightedQuad(np.ones(n)),
        "ActivationModelSmooth1Norm": lambda n: c.ActivationModelSmooth1Norm(n, 0.1),
        "ActivationModelSmooth2Norm": lambda n: c.ActivationModelSmooth2Norm(n, 0.1),
        "ActivationModelQuadFlatLog": lambda n: c.ActivationModelQuadFlatLog(n, 0.3),
        "ActivationModelQuadFlatExp": lambda n: c.ActivationModelQuadFlatExp(n, 0.3),
        "ActivationModelQuadraticBarrier": lambda n: c.ActivationModelQuadraticBarrier(
            c.ActivationBounds(-np.ones(n), np.ones(n))),
        "ActivationModelWeightedQuadraticBarrier": lambda n: c.ActivationModelWeightedQuadraticBarrier(
            c.ActivationBounds(-np.ones(n), np.ones(n)), np.ones(n)),
        "ActivationModel2NormBarrier": lambda n: c.ActivationModel2NormBarrier(n, 0.5),
    }
    for name, make in acts.items():
        def calc(r, make=make):
            act = make(3)
            d = act.createData()
            act.calc(d, r)
            act.calcDiff(d, r)
            return d
        yield from _cases_of(name + ".calc", calc, {"r": np.zeros(3)}, {"r": bad_vectors(3)})
        yield from _extreme(name + ".calc", calc, 3, "r")
    yield from _cases_of("ActivationModelQuad", c.ActivationModelQuad, {"nr": 3}, {"nr": COUNTS})
    yield from _cases_of("ActivationModelWeightedQuad", c.ActivationModelWeightedQuad, {"weights": np.ones(3)},
                         {"weights": sizeless(bad_vectors(3))})
    for name in ("ActivationModelSmooth1Norm", "ActivationModelSmooth2Norm"):
        yield from _cases_of(name, getattr(c, name), {"nr": 3, "eps": 0.1},
                             {"nr": COUNTS, "eps": NUMBERS + NEGATIVE})
    for name in ("ActivationModelQuadFlatLog", "ActivationModelQuadFlatExp", "ActivationModel2NormBarrier"):
        yield from _cases_of(name, getattr(c, name), {"nr": 3, "alpha": 0.3},
                             {"nr": COUNTS, "alpha": NUMBERS + NEGATIVE})
    inf3 = np.full(3, np.inf)
    yield from _cases_of("ActivationBounds", c.ActivationBounds, {"lb": -np.ones(3), "ub": np.ones(3), "beta": 1.0},
                         {"lb": bad_vectors(3) + [("+inf", inf3), ("above-ub", 2 * np.ones(3))],
                          "ub": [b for b in bad_vectors(3) if b[0] != "inf"] + [("-inf", -inf3)],
                          "beta": NUMBERS + NEGATIVE})

    for op, names in (("diff", ("x0", "x1")), ("integrate", ("x", "dx")), ("Jdiff", ("x0", "x1")),
                      ("Jintegrate", ("x", "dx"))):
        for k in range(2):
            def call(v, op=op, k=k):
                args = [np.zeros(4), np.zeros(4)]
                args[k] = v
                return getattr(sv, op)(*args)
            yield from ((f"StateVector.{op}", names[k], lab, (lambda v=v, call=call: call(v)), False, v)
                        for lab, v in bad_vectors(4))
            yield from _extreme(f"StateVector.{op}", call, 4, names[k])
    yield from _cases_of("StateVector", c.StateVector, {"nx": 3}, {"nx": COUNTS})

    def residual_state(xref, nu=2):
        return c.ResidualModelState(sv, xref, nu)
    yield from _cases_of("ResidualModelState", residual_state, {"xref": np.zeros(4)},
                         {"xref": [b for b in bad_vectors(4) if b[0] not in ("none", "int")],
                          "nu": [b for b in COUNTS if b[0] != "none"]})

    def residual_state_ref(xref):
        c.ResidualModelState(sv, np.zeros(4), 2).reference = xref
    yield from _cases_of("ResidualModelState.reference", residual_state_ref, {"xref": np.ones(4)},
                         {"xref": bad_vectors(4)})

    def residual_control(uref):
        return c.ResidualModelControl(sv, uref)
    yield from _cases_of("ResidualModelControl", residual_control, {"uref": np.ones(2)},
                         {"uref": [b for b in sizeless(bad_vectors(2)) if b[0] not in ("none", "int")]})

    def residual_control_ref(uref):
        c.ResidualModelControl(sv, np.zeros(2)).reference = uref
    yield from _cases_of("ResidualModelControl.reference", residual_control_ref, {"uref": np.ones(2)},
                         {"uref": bad_vectors(2)})

    def cost_sum():
        costs = c.CostModelSum(sv, 2)
        costs.addCost("x", c.CostModelResidual(sv, c.ResidualModelState(sv, np.ones(4), 2)), 2.0)
        costs.addCost("u", c.CostModelResidual(
            sv, c.ActivationModelSmooth1Norm(2, 0.1), c.ResidualModelControl(sv, 2)), 0.5)
        return costs

    def add_cost(name, weight, active):
        cost_sum().addCost(name, c.CostModelResidual(sv, c.ResidualModelControl(sv, 2)), weight, active)
    yield from _cases_of("CostModelSum.addCost", add_cost, {"name": "new", "weight": 1.0, "active": True},
                         {"name": KEYS, "weight": NUMBERS, "active": BOOLS})
    yield from _cases_of("CostModelSum.changeCostStatus", lambda name, active: cost_sum().changeCostStatus(
        name, active), {"name": "x", "active": False}, {"name": KEYS + [("unknown", "zz")], "active": BOOLS})

    def set_weight(weight):
        cost_sum().costs["x"].weight = weight
    yield from _cases_of("CostItem.weight", set_weight, {"weight": 2.0}, {"weight": NUMBERS})
    models = {
        "ResidualModelState": lambda: c.ResidualModelState(sv, np.ones(4), 2),
        "ResidualModelControl": lambda: c.ResidualModelControl(sv, np.ones(2)),
        "CostModelResidual": lambda: c.CostModelResidual(sv, c.ResidualModelState(sv, np.zeros(4), 2)),
        "CostModelSum": cost_sum,
    }
    for name, make in models.items():
        for k, arg in enumerate(("x", "u")):
            def calc(v, make=make, k=k):
                model = make()
                d = model.createData(c.DataCollectorAbstract())
                args = [np.zeros(4), np.zeros(2)]
                args[k] = v
                model.calc(d, *args)
                model.calcDiff(d, *args)
                return d
            values = bad_vectors(4 if k == 0 else 2)
            yield from ((f"{name}.calc", arg, lab, (lambda v=v, calc=calc: calc(v)), False, v) for lab, v in values
                        if not (k == 1 and lab == "none"))
            yield from _extreme(f"{name}.calc", calc, 4 if k == 0 else 2, arg)
    yield from action_cases()


def action_cases() -> Iterator[Case]:
    import crocopy as c

    actions = {
        "ActionModelUnicycle": c.ActionModelUnicycle,
        "ActionModelLQR": lambda: c.ActionModelLQR.Random(3, 2),
        "IntegratedActionModelEuler": lambda: c.IntegratedActionModelEuler(c.DifferentialActionModelLQR.Random(2, 2),
                                                                          0.05),
        "IntegratedActionModelRK": lambda: c.IntegratedActionModelRK(
            c.DifferentialActionModelLQR.Random(2, 2), c.RKType.four, 0.05),
    }
    for name, make in actions.items():
        for k, arg in enumerate(("x", "u")):
            def calc(v, make=make, k=k):
                model = make()
                d = model.createData()
                args = [np.zeros(model.state.nx), np.zeros(model.nu)]
                args[k] = v
                model.calc(d, *args)
                model.calcDiff(d, *args)
                return d
            n = make().state.nx if k == 0 else make().nu
            yield from ((f"{name}.calc", arg, lab, (lambda v=v, calc=calc: calc(v)), False, v)
                        for lab, v in bad_vectors(n) if not (k == 1 and lab == "none"))
            yield from _extreme(f"{name}.calc", calc, n, arg)
        for bound, wrong in (("u_lb", ("+inf", np.full(2, np.inf))), ("u_ub", ("-inf", np.full(2, -np.inf)))):
            values = [b for b in bad_vectors(2) if not (bound == "u_ub" and b[0] == "inf")] + [wrong]
            yield from _cases_of(f"{name}.{bound}", lambda make=make, bound=bound, **kw: setattr(
                make(), bound, kw[bound]), {bound: np.zeros(2)}, {bound: values})
        if "Integrated" in name or name == "ActionModelUnicycle":
            yield from _cases_of(f"{name}.dt", lambda dt, make=make: setattr(make(), "dt", dt), {"dt": 0.1},
                                 {"dt": NUMBERS + NEGATIVE})
    yield from _cases_of("IntegratedActionModelEuler", lambda timeStep: c.IntegratedActionModelEuler(
        c.DifferentialActionModelLQR.Random(2, 2), timeStep), {"timeStep": 0.1},
        {"timeStep": [b for b in NUMBERS + NEGATIVE if b[0] != "none"]})  # None: the default step
    yield from _cases_of("ActionModelUnicycle.costWeights", lambda costWeights: setattr(
        c.ActionModelUnicycle(), "costWeights", costWeights), {"costWeights": np.ones(2)},
        {"costWeights": bad_vectors(2)})
    unicycle = c.ActionModelUnicycle()
    yield from _cases_of("ShootingProblem", lambda x0: c.ShootingProblem(x0, [unicycle] * 3, unicycle),
                         {"x0": np.zeros(3)},
                         {"x0": bad_vectors(3)})


def multibody_cases() -> Iterator[Case]:
    import pinocchio as pin

    import crocopy as c

    st = mb_state("solo12")
    fid = st.pinocchio.getFrameId("FL_FOOT")
    x = mb_point(st)
    R = pin.SE3.Identity()
    yield from _cases_of("StateMultibody", c.StateMultibody, {"model": st.pinocchio},
                         {"model": [("none", None), ("string", "solo"), ("int", 3)]})
    for op, names in (("diff", ("x0", "x1")), ("integrate", ("x", "dx"))):
        for k in range(2):
            def call(v, op=op, k=k):
                args = [x.copy(), x.copy() if op == "diff" else np.zeros(st.ndx)]
                args[k] = v
                return getattr(st, op)(*args)
            size = st.nx if (op == "diff" or k == 0) else st.ndx
            yield from ((f"StateMultibody.{op}", names[k], lab, (lambda v=v, call=call: call(v)), False, v)
                        for lab, v in bad_vectors(size))
            yield from _extreme(f"StateMultibody.{op}", call, size, names[k])
    frames = {
        "ResidualModelFrameTranslation": (c.ResidualModelFrameTranslation, "xref", np.zeros(3), bad_vectors(3)),
        "ResidualModelFrameRotation": (c.ResidualModelFrameRotation, "Rref", np.eye(3), bad_rotations()),
        "ResidualModelFramePlacement": (c.ResidualModelFramePlacement, "pref", R, bad_placements()),
        "ResidualModelContactForce": (lambda state, id, fref, nu: c.ResidualModelContactForce(
            state, id, fref, 6, nu), "fref", pin.Force.Zero(), bad_spatial("Force")),
    }
    for name, (cls, ref, good, bads) in frames.items():
        yield from _cases_of(name, cls, {"state": st, "id": fid, ref: good, "nu": 12},
                             {"id": FRAMES, ref: bads, "nu": [b for b in COUNTS if b[0] != "none"],
                              "state": [("none", None), ("vector-state", c.StateVector(3))]})
        yield from _cases_of(f"{name}.reference", lambda cls=cls, ref=ref, good=good, **kw: setattr(
            cls(st, fid, good, 12), "reference", kw[ref]), {ref: good}, {ref: bads})
    yield from _cases_of("ResidualModelFrameVelocity", c.ResidualModelFrameVelocity,
                         {"state": st, "id": fid, "vref": pin.Motion.Zero(), "type": pin.LOCAL, "nu": 12},
                         {"id": FRAMES, "vref": bad_spatial("Motion"), "type": FRAME_TYPES})
    yield from _cases_of("ResidualModelCoMPosition", c.ResidualModelCoMPosition, {"state": st, "cref": np.zeros(3)},
                         {"cref": bad_vectors(3)})
    residual = c.ResidualModelFrameTranslation(st, fid, np.zeros(3), 12)
    for k, arg in enumerate(("x", "u")):
        def calc(v, k=k):
            d = residual.createData(pinocchio_collector(st))
            args = [x.copy(), np.zeros(12)]
            args[k] = v
            residual.calc(d, *args)
            residual.calcDiff(d, *args)
            return d
        n = st.nx if k == 0 else 12
        yield from (("ResidualModelFrameTranslation.calc", arg, lab, (lambda v=v, calc=calc: calc(v)), False, v)
                    for lab, v in bad_vectors(n) if not (k == 1 and lab == "none"))
    contacts = {
        "ContactModel3D": (lambda state, id, xref, type, nu, gains: c.ContactModel3D(state, id, xref, type, nu, gains),
                           "xref", np.zeros(3), bad_vectors(3)),
        "ContactModel6D": (lambda state, id, pref, type, nu, gains: c.ContactModel6D(state, id, pref, type, nu, gains),
                           "pref", R, bad_placements()),
    }
    for name, (cls, ref, good, bads) in contacts.items():
        yield from _cases_of(name, cls, {"state": st, "id": fid, ref: good, "type": pin.LOCAL, "nu": 12,
                                         "gains": np.array([0.0, 50.0])},
                             {"id": FRAMES, ref: bads, "type": FRAME_TYPES,
                              "gains": [b for b in bad_vectors(2) if b[0] != "none"]})
        yield from _cases_of(f"{name}.reference", lambda cls=cls, ref=ref, good=good, **kw: setattr(
            cls(st, fid, good, pin.LOCAL, 12, None), "reference", kw[ref]), {ref: good}, {ref: bads})
    yield from _cases_of("ContactModel1D", c.ContactModel1D,
                         {"state": st, "id": fid, "xref": 0.0, "type": pin.LOCAL, "rotation": np.eye(3), "nu": 12},
                         {"xref": NUMBERS, "rotation": [b for b in bad_rotations() if b[0] != "none"]})

    def add_contact(name, active):
        cm = c.ContactModelMultiple(st, 12)
        cm.addContact(name, c.ContactModel3D(st, fid, np.zeros(3), pin.LOCAL, 12), active)
    yield from _cases_of("ContactModelMultiple.addContact", add_contact, {"name": "fl", "active": True},
                         {"name": KEYS, "active": BOOLS})

    def change_contact(name, active):
        cm = c.ContactModelMultiple(st, 12)
        cm.addContact("fl", c.ContactModel3D(st, fid, np.zeros(3), pin.LOCAL, 12))
        cm.changeContactStatus(name, active)
    yield from _cases_of("ContactModelMultiple.changeContactStatus", change_contact, {"name": "fl", "active": False},
                         {"name": KEYS + [("unknown", "zz")], "active": BOOLS})
    yield from _cases_of("FrictionCone", c.FrictionCone, {"R": np.eye(3), "mu": 0.7, "nf": 4, "inner_appr": True,
                                                          "min_nforce": 0.0, "max_nforce": np.inf},
                         {"R": [b for b in bad_rotations() if b[0] != "none"], "mu": NUMBERS + NEGATIVE, "nf": COUNTS,
                          "inner_appr": BOOLS, "min_nforce": NUMBERS, "max_nforce": [("nan", np.nan),
                                                                                      ("below-min", -1.0)]})
    act = c.ActuationModelFloatingBase(st)
    for k, arg in enumerate(("x", "u")):
        def act_calc(v, k=k):
            ad = act.createData()
            args = [x.copy(), np.zeros(act.nu)]
            args[k] = v
            act.calc(ad, *args)
            act.calcDiff(ad, *args)
            return ad
        n = st.nx if k == 0 else act.nu
        yield from (("ActuationModelFloatingBase.calc", arg, lab, (lambda v=v, f=act_calc: f(v)), False, v)
                    for lab, v in bad_vectors(n) if not (k == 1 and lab == "none"))
        yield from _extreme("ActuationModelFloatingBase.calc", act_calc, n, arg) if k == 1 else iter(())


def more_cases() -> Iterator[Case]:
    """Cones, impulses, 2D contacts, momentum/effort residuals, constraints, state limits, contact dynamics
    options, problems and solvers."""
    import pinocchio as pin

    import crocopy as c

    st = mb_state("solo12")
    fid = st.pinocchio.getFrameId("FL_FOOT")
    x = mb_point(st)
    box = np.array([0.1, 0.05])
    yield from _cases_of("WrenchCone", c.WrenchCone, {"R": np.eye(3), "mu": 0.7, "box": box, "nf": 4},  # inf box:
                         {"R": [b for b in bad_rotations() if b[0] != "none"], "mu": NUMBERS + NEGATIVE,  # Crocoddyl's
                          "box": [b for b in bad_vectors(2) if b[0] not in ("none", "inf")] + [("negative", -box)],
                          "nf": COUNTS + [("odd", 3)]})
    yield from _cases_of("CoPSupport", c.CoPSupport, {"R": np.eye(3), "box": box},  # inf: Crocoddyl's default
                         {"R": [b for b in bad_rotations() if b[0] != "none"],
                          "box": [b for b in bad_vectors(2) if b[0] not in ("none", "inf")] + [("negative", -box)]})
    for name in ("ImpulseModel3D", "ImpulseModel6D"):
        yield from _cases_of(name, getattr(c, name), {"state": st, "frame": fid, "type": pin.LOCAL},
                             {"frame": FRAMES, "type": FRAME_TYPES})
    yield from _cases_of("ContactModel2D", c.ContactModel2D, {"state": st, "id": fid, "xref": np.zeros(2), "nu": 12},
                         {"id": FRAMES, "xref": bad_vectors(2), "nu": [b for b in COUNTS if b[0] != "none"]})
    yield from _cases_of("ResidualModelCentroidalMomentum", c.ResidualModelCentroidalMomentum,
                         {"state": st, "href": np.zeros(6), "nu": 12},
                         {"href": bad_vectors(6), "nu": [b for b in COUNTS if b[0] != "none"]})
    actuation = c.ActuationModelFloatingBase(st)
    yield from _cases_of("ResidualModelJointEffort", c.ResidualModelJointEffort,
                         {"state": st, "actuation": actuation, "uref": np.zeros(12), "nu": 12},
                         {"uref": [b for b in bad_vectors(12) if b[0] not in ("none", "int")]})
    yield from _cases_of("ResidualModelJointAcceleration", c.ResidualModelJointAcceleration,
                         {"state": st, "aref": np.zeros(st.nv), "nu": 12},
                         {"aref": [b for b in bad_vectors(st.nv) if b[0] not in ("none", "int")]})
    cone = c.FrictionCone(np.eye(3), 0.7)
    yield from _cases_of("ResidualModelContactFrictionCone", c.ResidualModelContactFrictionCone,
                         {"state": st, "id": fid, "fref": cone, "nu": 12},
                         {"id": FRAMES, "fref": [("none", None), ("matrix", np.eye(3)), ("string", "cone")],
                          "nu": [b for b in COUNTS if b[0] != "none"]})
    sv = c.StateVector(3)
    residual = c.ResidualModelState(sv, np.zeros(3), 2)
    yield from _cases_of("ConstraintModelResidual", lambda lower, upper: c.ConstraintModelResidual(
        sv, residual, lower, upper), {"lower": -np.ones(3), "upper": np.ones(3)},
        {"lower": bad_vectors(3) + [("+inf", np.full(3, np.inf)), ("above-ub", 2 * np.ones(3))],
         "upper": [b for b in bad_vectors(3) if b[0] != "inf"] + [("-inf", np.full(3, -np.inf))]})
    for bound, upper in (("lb", False), ("ub", True)):
        values = [b for b in bad_vectors(3) if not (upper and b[0] == "inf")]
        values.append(("-inf", np.full(3, -np.inf)) if upper else ("+inf", np.full(3, np.inf)))
        yield from _cases_of(f"StateVector.{bound}", lambda bound=bound, **kw: setattr(
            c.StateVector(3), bound, kw[bound]), {bound: np.zeros(3)}, {bound: values})
    costs = c.CostModelSum(st, 12)
    costs.addCost("x", c.CostModelResidual(st, c.ResidualModelState(st, st.zero(), 12)), 1.0)
    contacts = c.ContactModelMultiple(st, 12)
    for foot in ("FL_FOOT", "FR_FOOT", "HL_FOOT"):
        contacts.addContact(foot, c.ContactModel3D(st, foot, np.zeros(3), pin.LOCAL, 12, np.array([0.0, 50.0])))
    yield from _cases_of("DifferentialActionModelContactFwdDynamics",
                         lambda inv_damping, enable_force: c.DifferentialActionModelContactFwdDynamics(
                             st, actuation, contacts, costs, None, inv_damping, enable_force),
                         {"inv_damping": 0.0, "enable_force": True},
                         {"inv_damping": NUMBERS + NEGATIVE, "enable_force": BOOLS})
    unicycle = c.ActionModelUnicycle()
    problem = c.ShootingProblem(np.zeros(3), [unicycle] * 3, unicycle)
    xs, us = [np.zeros(3)] * 4, [np.zeros(2)] * 3

    def problem_calc(xs, us):
        return problem.calc(xs, us)
    yield from _cases_of("ShootingProblem.calc", problem_calc, {"xs": xs, "us": us},
                         {"xs": [("short", xs[:-1]), ("none", None), ("string", "xs"),
                                 ("nan", [np.full(3, np.nan)] * 4), ("item", [np.zeros(2)] * 4),
                                 ("complex", [np.zeros(3) + 1j] * 4)],
                          "us": [("long", us + us[:1]), ("none", None), ("item", [np.zeros(3)] * 3),
                                 ("inf", [np.full(2, np.inf)] * 3)]})
    finite = [b for b in NUMBERS + NEGATIVE if b[0] != "inf"]  # +inf: no threshold / no maximum
    for setting, values in (("th_stop", finite), ("reg_min", NUMBERS + NEGATIVE), ("reg_max", finite),
                            ("th_acceptStep", NUMBERS + NEGATIVE)):
        yield from _cases_of(f"SolverFDDP.{setting}", lambda setting=setting, **kw: setattr(
            c.SolverFDDP(problem), setting, kw[setting]), {setting: 0.1}, {setting: values})

    def solve(maxiter, is_feasible, init_reg):
        c.SolverFDDP(problem).solve([], [], maxiter, is_feasible, init_reg)
    yield from _cases_of("SolverFDDP.solve", solve, {"maxiter": 2, "is_feasible": False, "init_reg": None},
                         {"maxiter": COUNTS, "is_feasible": BOOLS,
                          "init_reg": [b for b in NUMBERS + NEGATIVE if b[0] not in ("none", "nan")]})  # the defaults
    yield from _cases_of("ResidualModelFrameVelocity.type", lambda type: setattr(c.ResidualModelFrameVelocity(
        st, fid, pin.Motion.Zero(), pin.LOCAL, 12), "type", type), {"type": pin.WORLD}, {"type": FRAME_TYPES})
    yield from _cases_of("ContactModel3D.gains", lambda gains: setattr(c.ContactModel3D(
        st, fid, np.zeros(3), pin.LOCAL, 12), "gains", gains), {"gains": np.ones(2)},
        {"gains": [b for b in bad_vectors(2) if b[0] != "none"]})
    yield from _cases_of("ActionModelSquashed", lambda smooth, s_lb: c.ActionModelSquashed(
        unicycle, "smooth-sat", s_lb, np.ones(2), smooth), {"smooth": 2.0, "s_lb": -np.ones(2)},
        {"smooth": NUMBERS + NEGATIVE, "s_lb": bad_vectors(2)[:-1]})
    yield from _cases_of("SquashingModelSmoothSat", lambda u_lb, ns: c.SquashingModelSmoothSat(
        u_lb, np.ones(2), ns), {"u_lb": -np.ones(2), "ns": 2},
        {"u_lb": [b for b in bad_vectors(2) if b[0] != "none"], "ns": [b for b in COUNTS if b[0] != "list"]})
    yield from _cases_of("ActionModelControlPenalty", lambda weight, lb: c.ActionModelControlPenalty(
        unicycle, weight, lb), {"weight": 10.0, "lb": -np.ones(2)},
        {"weight": NUMBERS + NEGATIVE,
         "lb": [b for b in bad_vectors(2)[:-1] if b[0] != "none"] + [("+inf", np.full(2, np.inf))]})
    yield from _cases_of("BoxQP", c.BoxQP, {"nx": 2, "maxiter": 10, "th_acceptStep": 0.1, "th_grad": 1e-9, "reg": 1e-9},
                         {"nx": COUNTS, "maxiter": COUNTS, "th_acceptStep": NUMBERS + NEGATIVE,
                          "th_grad": NUMBERS + NEGATIVE, "reg": NUMBERS + NEGATIVE})
    del x


def cases() -> list[Case]:
    return list(core_cases()) + list(multibody_cases()) + list(more_cases())
