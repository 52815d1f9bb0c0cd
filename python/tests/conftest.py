"""Finds the built module: PYTHONPATH (scripts/test.sh sets it to <build>/python), else the
package beside the default build folder."""
import pathlib
import sys

try:
    import tridiff  # noqa: F401
except ImportError:
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "build" / "python"))
