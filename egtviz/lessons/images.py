"""The images a lesson's text may show: files of the lesson's own folder or of the package's assets.

A lesson names an image by its plain file name (``![The rig](rig.png)``). The server reads the file itself, when
the lesson is loaded, and puts its bytes in the text as a ``data:`` URL: a learner's browser never fetches an
address a lesson file wrote, and never names a path on the server. Anything else (an address, a path, another
file type, a symbolic link leading out of the folder, an image too large) is refused with the reason.
"""

from __future__ import annotations

import base64
import re
from pathlib import Path

from ..files import FileSafetyError, printable, read_limited
from ..resources import shipped_folder
from ..scene.limits import MAX_LESSON_IMAGE_BYTES, MAX_LESSON_IMAGES_BYTES

__all__ = ["IMAGE_TYPES", "ImageError", "LessonImages"]

IMAGE_TYPES = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".gif": "image/gif",
               ".webp": "image/webp"}
"""The image files a lesson may show, by suffix (any case)."""

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}")
_MAGIC = {
    "image/png": (b"\x89PNG\r\n\x1a\n",),
    "image/jpeg": (b"\xff\xd8\xff",),
    "image/gif": (b"GIF87a", b"GIF89a"),
}


class ImageError(ValueError):
    """An image a lesson's text cannot show; the message says why."""


def _is_type(data: bytes, mime: str) -> bool:
    if mime == "image/webp":
        return data[:4] == b"RIFF" and data[8:12] == b"WEBP"
    return data.startswith(_MAGIC[mime])


class LessonImages:
    """Reads the images of one lesson (its folder first, then the package's assets), counting their bytes.

    Each use of an image counts towards :data:`~egtviz.scene.limits.MAX_LESSON_IMAGES_BYTES`, since each use is
    embedded in the text the server sends.
    """

    def __init__(self, folder: Path | None) -> None:
        """``folder``: the lesson file's folder (None: a lesson read from text shows only the package's assets)."""
        self.folders = tuple(f for f in (folder, shipped_folder("assets")) if f is not None)
        self.total = 0
        """Bytes of the images used so far."""

    def data_url(self, target: str) -> str:
        """The image ``target`` names, as a ``data:`` URL.

        Raises:
            ImageError: ``target`` is not a plain name of an image file in the lesson's folder or the assets, or
                the image is not what its suffix says, or too large.
        """
        shown = printable(target[:80])
        outside = ("images come only from the lesson's folder or egtviz's assets, named by their file name "
                   "(e.g. rig.png)")
        if not _NAME.fullmatch(target):
            raise ImageError(f"image {shown!r}: {outside}; an address or a path is not shown")
        mime = IMAGE_TYPES.get(Path(target).suffix.lower())
        if mime is None:
            raise ImageError(f"image {shown!r}: expected a {', '.join(IMAGE_TYPES)} file")
        data = self._read(target, shown)
        if not _is_type(data, mime):
            raise ImageError(f"image {shown!r}: not a {mime.split('/')[1].upper()} file")
        self.total += len(data)
        if self.total > MAX_LESSON_IMAGES_BYTES:
            raise ImageError(f"image {shown!r}: the lesson's images come to more than {MAX_LESSON_IMAGES_BYTES:,} "
                             "bytes (each use counted)")
        return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"

    def _read(self, name: str, shown: str) -> bytes:
        for folder in self.folders:
            path = folder / name
            if not path.exists():
                continue
            # A link inside the folder is fine; one leading out of it is refused like a path.
            if path.resolve().parent != folder.resolve():
                raise ImageError(f"image {shown!r}: a symbolic link leading out of its folder")
            try:
                return read_limited(path, MAX_LESSON_IMAGE_BYTES)
            except FileSafetyError as exc:
                raise ImageError(f"image {shown!r}: {str(exc).removeprefix(printable(str(path)) + ': ')}") from None
        raise ImageError(f"image {shown!r}: no such file in the lesson's folder or egtviz's assets")
