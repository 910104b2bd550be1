"""ocellus: fast, biologically inspired active vision (the Rust library, from Python).

Arrays are numpy, row-major, indexed ``[y, x]``; images are ``uint8`` (0..255) or ``float32``
(0..1), H x W (grey) or H x W x 3 (RGB); pixel centres sit at integer coordinates. Maps come
back as ``float32`` arrays that own the library's buffers. Heavy calls release the GIL.
Errors raise :class:`OcellusError` (a ``ValueError``) with the library's message.
"""

from ._ocellus import (
    GroundSequence,
    LogPolar,
    OcellusError,
    Odometry,
    SaliencyEngine,
    StreamEngine,
    auc_borji,
    auc_judd,
    calibrate_chessboard,
    cc,
    decompose,
    dlt,
    ig,
    kl,
    logpolar,
    nss,
    presets,
    read_image,
    register,
    saliency,
    sauc,
    sim,
    stereo_bm,
    stereo_sgm,
    triangulate,
    undistort,
    vergence,
)

__all__ = [
    "GroundSequence",
    "LogPolar",
    "OcellusError",
    "Odometry",
    "SaliencyEngine",
    "StreamEngine",
    "auc_borji",
    "auc_judd",
    "calibrate_chessboard",
    "cc",
    "decompose",
    "dlt",
    "ig",
    "kl",
    "logpolar",
    "nss",
    "presets",
    "read_image",
    "register",
    "saliency",
    "sauc",
    "sim",
    "stereo_bm",
    "stereo_sgm",
    "triangulate",
    "undistort",
    "vergence",
]
