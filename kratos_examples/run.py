#!/usr/bin/env python3
"""Runs the Kratos model of DIR (make_model.py) with GeoMechanicsAnalysis and writes
DIR/steps.json: per converged step its time, Newton iterations, cycles (1 + the times
Kratos halved the step), and at every integration point the strain and the stress
(Kratos's order [xx, yy, zz, xy]) and the first STATE_VARIABLES entries as the element
reports them. MESORVE_UMAT_SCENE names the RVE scene (the caller sets it).

Usage: run.py DIR
"""
import json
import os
import sys

import KratosMultiphysics as KM
import KratosMultiphysics.GeoMechanicsApplication as Geo
from KratosMultiphysics.GeoMechanicsApplication.geomechanics_analysis import GeoMechanicsAnalysis


def var(name):
    return KM.KratosGlobals.GetVariable(name)


def point_values(element, variable, info):
    return [list(v) for v in element.CalculateOnIntegrationPoints(variable, info)]


class Recorded(GeoMechanicsAnalysis):
    """GeoMechanicsAnalysis that keeps each converged step's values."""

    def __init__(self, model, parameters):
        super().__init__(model, parameters)
        self.steps = []

    def FinalizeSolutionStep(self):
        super().FinalizeSolutionStep()
        part = self._GetSolver().GetComputingModelPart()
        info = part.ProcessInfo
        points = []
        for e in part.Elements:
            stress = point_values(e, KM.CAUCHY_STRESS_VECTOR, info)
            strain = point_values(e, var("ENGINEERING_STRAIN_VECTOR"), info)
            state = point_values(e, var("STATE_VARIABLES"), info)
            first = e.CalculateOnIntegrationPoints(var("STATE_VARIABLE_1"), info)
            for s, t, v, w in zip(stress, strain, state, first):
                points.append({"stress": s, "strain": t, "element_state": v[:3],
                               "element_state_len": len(v), "state_variable_1": w})
        self.steps.append({"time": info[KM.TIME],
                           "iterations": info[KM.NL_ITERATION_NUMBER],
                           "cycles": info[KM.NUMBER_OF_CYCLES], "points": points})


def main():
    folder = sys.argv[1]
    os.chdir(folder)
    if not os.environ.get("KRATOS_INFO"):
        KM.Logger.GetDefaultOutput().SetSeverity(KM.Logger.Severity.WARNING)
    with open("ProjectParameters.json") as f:
        parameters = KM.Parameters(f.read())
    analysis = Recorded(KM.Model(), parameters)
    analysis.Run()
    with open("steps.json", "w") as f:
        json.dump(analysis.steps, f)
    for s in analysis.steps:
        sxx = [p["stress"][0] for p in s["points"]]
        print(f"time {s['time']:.4f}: {s['iterations']} Newton iteration(s), cycle "
              f"{s['cycles']}, sigma_xx {min(sxx):.6f} .. {max(sxx):.6f} at "
              f"{len(sxx)} points")


if __name__ == "__main__":
    main()
