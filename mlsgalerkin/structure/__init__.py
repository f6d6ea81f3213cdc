"""Structures loaded by the fluid: elastic bodies on scikit-fem (work in progress, issue 11).

=========================================  ================================================
module                                     contents
=========================================  ================================================
:mod:`~mlsgalerkin.structure.elastic`      :class:`ElasticMaterial`, :class:`ElasticBody`:
                                           small-strain elasticity on a scikit-fem mesh,
                                           lumped mass, clamped facets, static solve and
                                           explicit central differences
=========================================  ================================================
"""

from mlsgalerkin.structure.elastic import ElasticBody, ElasticMaterial

__all__ = ["ElasticBody", "ElasticMaterial"]
