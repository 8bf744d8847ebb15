import os
import tempfile

# One kernel cache per test session unless the caller chose one: tests never
# depend on kernels left behind by other versions of the code.
os.environ.setdefault("BLADEMODEL_CACHE_DIR", os.path.join(tempfile.gettempdir(), "blademodel-test-cache"))
