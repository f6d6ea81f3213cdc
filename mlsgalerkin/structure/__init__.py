"""Structures loaded by the fluid: elastic bodies on scikit-fem and rigid bodies.

=============================================  ================================================
module                                         contents
=============================================  ================================================
:mod:`~mlsgalerkin.structure.elastic`          :class:`ElasticMaterial`, :class:`ElasticBody`:
                                               a scikit-fem mesh and element, stiffness, lumped
                                               mass, clamped facets, weight, the wet surface
:mod:`~mlsgalerkin.structure.rigid`            :class:`RigidBody`, :class:`Hinge`: mass,
                                               inertia, constraints, a surface of segments
:mod:`~mlsgalerkin.structure.explicit`         sub-cycled central differences in one numba
                                               call (and its numpy reference)
:mod:`~mlsgalerkin.structure.steppers`         how each body advances over an outer step,
                                               one stepper per method: central differences,
                                               Newmark, rigid motion; the live state
:mod:`~mlsgalerkin.structure.solver`           :class:`StructureSolver` in the run loop
=============================================  ================================================
"""

from mlsgalerkin.structure.elastic import ElasticBody, ElasticMaterial
from mlsgalerkin.structure.rigid import Hinge, RigidBody
from mlsgalerkin.structure.scheme import StructureScheme

__all__ = ["ElasticBody", "ElasticMaterial", "Hinge", "RigidBody", "StructureScheme"]
