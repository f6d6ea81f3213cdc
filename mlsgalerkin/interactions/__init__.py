"""Interactions between two bodies of a scene: forces exchanged once per step between their solvers
(the contract is :class:`~mlsgalerkin.dynamics.Interaction`).

==================================================  ==============================================
module                                              contents
==================================================  ==============================================
:mod:`~mlsgalerkin.interactions.penalty_contact`    :class:`PenaltyContact`: node-to-surface penalty
                                                    contact of one body's nodes on another's surface
:mod:`~mlsgalerkin.interactions.structure_coupling` :class:`StructureCoupling`: a fluid loads a
                                                    structure (wall particles riding on it) and the
                                                    structure bounds the fluid (penalty contact)
==================================================  ==============================================

The contact geometry, broad phase and penalty kernel these use are :mod:`mlsgalerkin.contact`;
what an interaction needs from a solver beyond :class:`~mlsgalerkin.dynamics.Solver` is declared
there as optional protocols (:class:`~mlsgalerkin.dynamics.DrivesWalls`,
:class:`~mlsgalerkin.dynamics.CarriesStepEndLoad`) and checked with the scene.
"""

from mlsgalerkin.interactions.penalty_contact import PenaltyContact
from mlsgalerkin.interactions.structure_coupling import AITKEN_RANGE, StructureCoupling, riding_kinematics

__all__ = ["AITKEN_RANGE", "PenaltyContact", "StructureCoupling", "riding_kinematics"]
