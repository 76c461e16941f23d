"""Files in and out: one module per kind of file or step, each named after what it computes.

::

    files.py          atomic writes (bytes, text, NPY, NPZ): temporary file, fsync, rename; the check that a
                      file to read exists
    output_folders.py all-or-nothing output folders (``output_dir``) and the checks of an output path made
                      before any work (``check_output_dir``, ``check_output_file``)
    exr.py            float32 / half EXR files: channel names, metadata, ZIP on OpenEXR's thread pool; reading
    images.py         ``read_image``: EXR, PNG, NPY or NPZ as a checked ``(H, W, C)`` float array
    tonemap.py        ``srgb8``: linear HDR -> exposure -> ACES filmic fit -> sRGB OETF -> 8-bit codes
    png.py            PNG previews: encoding with ``tEXt`` chunks, reading the chunks back, ``write_png``
    exposure.py       Rec. 709 luminance and the percentile exposure of previews
    render_files.py   a render's buffers as one EXR each plus its ``final.png`` preview

Conventions shared by all of them
---------------------------------
* Arrays are ``(H, W)`` or ``(H, W, C)``, row 0 = top row (EXR's natural ``INCREASING_Y`` order), linear
  HDR values.
* Every write is atomic (:func:`vlref.io.files.atomic_write`): the bytes go to a temporary file in the
  destination folder, are fsync'ed, then ``os.replace`` moves them into place; on any failure the temporary
  file is removed and no partial file remains. :func:`vlref.io.output_folders.output_dir` extends this to a
  set of files (all or nothing).
* Readers check type, shape, dtype, channel count and values (NaN always, inf on request) and raise
  :class:`vlref.errors.InputError` ``(file, field, reason)``.
"""
