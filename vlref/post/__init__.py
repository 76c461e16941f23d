"""Post passes of the volumetric-light pipeline, as pure functions over arrays.

``resolution`` (sizes, texel maps), ``downsample`` (depth), ``blur`` (separable depth-aware Gaussian),
``upsample`` (plain and depth-aware), ``composite`` (final image, storage rounding) and ``radial``
(GPU Gems 3 ch. 13 screen-space radial blur). Arrays are ``(H, W)`` / ``(H, W, C)`` with row 0 at the
top; every constant a source hard-codes is a keyword parameter defaulting to the source's value.
"""
