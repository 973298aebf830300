import sys

from psph.errors import record_stop_signals

record_stop_signals()  # before the heavy imports of the CLI (numba, mpi4py, h5py)

from psph.app.cli import main  # noqa: E402

sys.exit(main())
