"""Froxel volumetrics (Wronski 2014, Hillaire 2015): the camera-aligned grid, its passes and temporal reprojection.

``grid`` (slices, jitter, buffer layout), ``kernels`` (light, integrate, apply), ``temporal`` (history).
The technique that runs them is :mod:`vlref.techniques.froxel`.
"""
