"""Build a .jvpkg package of the ForaNav camera module (a bzip2 tar the camera unpacks into JEVOIS at boot).

Copy the file to JEVOIS:/packages/ and reboot the camera: it unpacks modules/<Vendor>/ForaNavTrees/ (module
files, models, script.cfg, params.cfg) and runs the package's postinstall once, which adds the USB-video and NONE
(headless) video mappings if they are missing. The same command gives the same bytes.
"""
import argparse
from pathlib import Path

from host_tools import fileio
from host_tools.deploy import module_files, package
from host_tools.deploy.modes import DEFAULT_MODE_TEXT, format_mode, parse_mode
from host_tools.errors import ForaNavError

PACKAGE_FILE_MODE = 0o644


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", required=True, metavar="FILE.jvpkg",
                        help="package file to write (JeVois only installs names ending in .jvpkg; "
                             "convention: ForaNav-ForaNavTrees.jvpkg)")
    parser.add_argument("--vendor", default=module_files.DEFAULT_VENDOR,
                        help="vendor folder under modules/ (default %(default)s)")
    parser.add_argument("--mode", default=DEFAULT_MODE_TEXT, metavar="WxH@FPS",
                        help="camera mode of the registered mappings (default %(default)s)")
    parser.add_argument("--module-dir", default=None, metavar="DIR",
                        help="module folder to package (default: the repository's jevois_module/ForaNavTrees)")


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.suffix != package.PACKAGE_SUFFIX:
        raise ForaNavError("--out %s: the camera only unpacks files ending in %s" % (out, package.PACKAGE_SUFFIX))
    fileio.check_output_file(out)
    mode = parse_mode(args.mode)
    vendor = module_files.check_name("vendor", args.vendor)
    folder = args.module_dir or module_files.default_module_folder()
    payload = module_files.build_module_payload(module_files.read_module_folder(folder), vendor, mode)
    members = package.package_members(payload.files, vendor, module_files.MODULE_NAME, mode)
    data = package.build_jvpkg(members)
    fileio.write_bytes(out, data)
    out.chmod(PACKAGE_FILE_MODE)  # the atomic writer's temporary file is private; a package is for sharing
    for note in payload.notes:
        print("note: " + note)
    print("%s: %d bytes, %d files under modules/%s/%s/ (%s). Copy it to JEVOIS:/packages/ and reboot the camera."
          % (out, len(data), len(members), vendor, module_files.MODULE_NAME, format_mode(mode)))
    return 0
