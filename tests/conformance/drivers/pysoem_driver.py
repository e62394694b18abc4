"""The conformance scenario through pysoem (SOEM 1.4 bundled): every step is in its API."""
import pysoem

from common import Recorder, parse_args
from soem_family import Api, run


def main():
    args, exp = parse_args()
    rec = Recorder(args.out, "pysoem", f"pysoem {pysoem.__version__}")
    m = pysoem.Master()
    m.open(args.iface)
    run(Api(pysoem), m, rec, exp)


if __name__ == "__main__":
    main()
