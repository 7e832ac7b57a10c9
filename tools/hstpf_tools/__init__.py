"""hstpf on the CAN bus: frame codec (DBC + E2E), simulator and tools.

See docs/tools.md for the command-line tools and docs/can.md for the frames.
"""

__version__ = "0.2.0"
