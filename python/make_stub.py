#!/usr/bin/env python3
"""Write vdb_ewa.pyi, the module's type stub, from the built module's own option list (render's
keywords are vdb_ewa render's options, so the stub is made from them, never by hand).

    PYTHONPATH=build/python python3 python/make_stub.py          # rewrite python/vdb_ewa.pyi
    PYTHONPATH=build/python python3 python/make_stub.py --check  # exit 1 if it is out of date (ctest)
"""
import os
import sys
import textwrap

import vdb_ewa

HEAD = '''"""Type stub of the vdb_ewa extension module (written by python/make_stub.py; do not edit)."""
import builtins
from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Number = Union[int, float]
OptionValue = Union[str, Number, bool, Sequence[Number], Sequence[Sequence[Number]], None]

class Error(RuntimeError): ...
class IoError(Error, OSError): ...
class InputError(Error): ...
class ValueError(Error, builtins.ValueError): ...
class BudgetError(Error, MemoryError): ...
class Cancelled(Error): ...
class RenderWarning(UserWarning): ...

class Grid:
    """{grid}"""
    @property
    def name(self) -> str: ...
    @property
    def path(self) -> str: ...
    @property
    def stored_type(self) -> str: ...
    @property
    def is_level_set(self) -> bool: ...
    @property
    def active_voxel_count(self) -> int: ...
    @property
    def active_tile_count(self) -> int: ...
    @property
    def world_centre(self) -> Tuple[float, float, float]: ...
    @property
    def voxel_length(self) -> float: ...
    def transformed(self, object_to_world: npt.ArrayLike) -> "Grid": ...
    def with_added_volume(self, other: "Grid") -> "Grid": ...
    def with_velocity_grid(self, name: str) -> "Grid": ...

class CancelToken:
    """{cancel}"""
    def __init__(self) -> None: ...
    def cancel(self) -> None: ...
    def reset(self) -> None: ...
    @property
    def cancelled(self) -> bool: ...

class Frame:
    """{frame}"""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def beauty(self) -> npt.NDArray[np.float32]: ...
    @property
    def aovs(self) -> Dict[str, npt.NDArray[np.float32]]: ...
    def aov(self, name: str) -> npt.NDArray[np.float32]: ...
    @property
    def stats(self) -> Dict[str, Any]: ...
    @property
    def coarse(self) -> bool: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def render_seconds(self) -> float: ...
    @property
    def metadata(self) -> Dict[str, str]: ...
    def write(self, path: Union[str, PathLike]) -> None: ...

class Scene:
    """{scene}"""
    def __init__(self, grid: Union[Grid, str, PathLike], **options: Any) -> None: ...
    def render(self, *, progress: Optional[Callable[[int], Optional[bool]]] = None, cancel: Optional[CancelToken] = None,
               progressive: Optional[Callable[["Frame"], Optional[bool]]] = None, **options: Any) -> Frame: ...
    def clear(self) -> None: ...
    @property
    def options(self) -> Dict[str, Any]: ...

def open(path: Union[str, PathLike], name: str = "") -> Grid: ...
def set_exr_threads(threads: int = 0) -> None: ...
def from_array(array: npt.ArrayLike, index_to_world: Optional[npt.ArrayLike] = None, name: str = "density", *,
               emission: Optional[npt.ArrayLike] = None, temperature: Optional[npt.ArrayLike] = None,
               velocity: Optional[npt.ArrayLike] = None) -> Grid: ...
'''

TYPES = {"bool": "Optional[bool]", "int": "Optional[int]", "float": "Optional[Number]", "str": "OptionValue"}


def stub() -> str:
    doc = lambda obj: obj.__doc__.strip().replace('"""', "'''")
    out = HEAD.format(grid=doc(vdb_ewa.Grid), cancel=doc(vdb_ewa.CancelToken), frame=doc(vdb_ewa.Frame), scene=doc(vdb_ewa.Scene))
    out += "def render(grid: Union[Grid, str, PathLike], *, progress: Optional[Callable[[int], Optional[bool]]] = None,\n"
    out += "           cancel: Optional[CancelToken] = None,\n"
    for keyword, option, kind, description in vdb_ewa._keywords():
        out += "           %s: %s = None,\n" % (keyword, TYPES[kind])
    out += "           ) -> Frame:\n"
    out += '    """Render a grid as `vdb_ewa render` would; the keywords are its options (help(vdb_ewa.render)):\n\n'
    for keyword, option, kind, description in vdb_ewa._keywords():
        text = "%s (%s): %s" % (keyword, option, description.replace('"""', "'''").replace("\\", "\\\\"))
        out += textwrap.indent(textwrap.fill(text, 100, subsequent_indent="    "), "    ") + "\n"
    out += '    """\n'
    return out


def main() -> int:
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "vdb_ewa.pyi")
    text = stub()
    if "--check" in sys.argv[1:]:
        with open(path) as f:
            if f.read() != text:
                print("%s is out of date: run python/make_stub.py with the built module on PYTHONPATH" % path)
                return 1
        print("%s matches the module" % path)
        return 0
    with open(path, "w") as f:
        f.write(text)
    print("wrote", path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
