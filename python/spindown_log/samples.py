"""Per-bench sample arrays from a log's SAMPLE messages: one entry per recorded sample, in log
order, as `spindown export --csv` writes them (repeats and NaN kept)."""

try:
    import numpy
except ImportError:  # the reader works without NumPy: lists instead of arrays
    numpy = None

UNITS = {0: "V", 1: "rpm", 2: "rad/s"}  # samples_t.QUANTITY_*

FIELDS = ("seq", "device_time_us", "host_time_us", "value", "raw_adc", "clock_epoch", "quantity", "log_time_us")
_DTYPES = {"seq": "int64", "device_time_us": "int64", "host_time_us": "int64", "value": "float64",
           "raw_adc": "int32", "clock_epoch": "int32", "quantity": "int8", "log_time_us": "int64"}


def unit_of(quantity):
    """The unit of samples_t.quantity: "V", "rpm", "rad/s" (or "code N" for an unknown one)."""
    return UNITS.get(quantity, "code %d" % quantity)


class BenchSamples:
    """The samples of one bench. Each field holds one entry per sample: NumPy arrays when NumPy is
    there (and not turned off), lists otherwise.

    seq             bridge sequence number (gaps mean lost samples)
    device_time_us  device clock, µs (device_time_s: seconds)
    host_time_us    host time the line was complete, µs since the epoch (host_time_s: seconds)
    value           the reading, in unit_of(quantity): back-EMF V, rpm or rad/s
    raw_adc         raw ADC counts, -1 when the protocol does not carry them
    clock_epoch     device resets seen by the bridge
    quantity        samples_t.QUANTITY_* of the message
    log_time_us     when the logger received the message (the event's timestamp)
    """

    def __init__(self, bench, columns, use_numpy):
        self.bench = bench
        self.numpy = use_numpy
        for name in FIELDS:
            col = columns[name]
            setattr(self, name, numpy.array(col, dtype=_DTYPES[name]) if use_numpy else col)

    def __len__(self):
        return len(self.seq)

    def _seconds(self, us):
        return us * 1e-6 if self.numpy else [x * 1e-6 for x in us]

    @property
    def device_time_s(self):
        return self._seconds(self.device_time_us)

    @property
    def host_time_s(self):
        return self._seconds(self.host_time_us)

    @property
    def units(self):
        """The unit of each distinct quantity in these samples (normally one)."""
        return sorted({unit_of(int(q)) for q in self.quantity})

    def __repr__(self):
        return "BenchSamples(%r, %d samples, %s)" % (self.bench, len(self), "numpy" if self.numpy else "lists")


class SampleCollector:
    """Takes SAMPLE messages one by one; arrays() gives {bench: BenchSamples} in order of first appearance."""

    def __init__(self):
        self._columns = {}

    def add(self, bench, msg, log_time_us):
        cols = self._columns.get(bench)
        if cols is None:
            cols = self._columns[bench] = {name: [] for name in FIELDS}
        n = msg.n
        cols["seq"].extend(range(msg.seq, msg.seq + n))
        cols["device_time_us"].extend(msg.device_time_us)
        cols["host_time_us"].extend(msg.host_time_us)
        cols["value"].extend(msg.value)
        cols["raw_adc"].extend(msg.raw_adc)
        cols["clock_epoch"].extend([msg.clock_epoch] * n)
        cols["quantity"].extend([msg.quantity] * n)
        cols["log_time_us"].extend([log_time_us] * n)

    def arrays(self, use_numpy=None):
        if use_numpy is None:
            use_numpy = numpy is not None
        if use_numpy and numpy is None:
            raise ImportError("NumPy is not installed (Debian: apt-get install python3-numpy); use numpy=False for lists")
        return {bench: BenchSamples(bench, cols, use_numpy) for bench, cols in self._columns.items()}
