"""Install the ForaNav camera module on a JeVois-A33 microSD card (its mounted JEVOIS partition).

Copies the module folder with its model files to modules/<Vendor>/ForaNavTrees/ with a generated script.cfg
(T2 lines to the 4-pin serial port) and params.cfg; adds a USB-video and a NONE (headless) mapping to
config/videomappings.cfg; with --headless, makes config/initscript.cfg start the module at power-on. Idempotent:
a second run changes nothing. Your edits to the card's params.cfg and script.cfg are kept (merged into the new
ones; the output says what was kept). Everything is checked before the first write; every changed file is backed
up first (<file>.foranav-bak-<n>) and written atomically. A write-protected file is left alone unless --force.
--dry-run prints the plan and writes nothing.
"""
import argparse
from pathlib import Path

from host_tools.deploy import card, module_files
from host_tools.deploy.modes import DEFAULT_MODE_TEXT, CameraMode, format_mode, is_calibrated_size, parse_mode


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--sd", required=True, metavar="PATH",
                        help="mount point of the card's JEVOIS partition (it has config/ and modules/)")
    parser.add_argument("--vendor", default=module_files.DEFAULT_VENDOR,
                        help="vendor folder under modules/ (default %(default)s)")
    parser.add_argument("--mode", default=DEFAULT_MODE_TEXT, metavar="WxH@FPS",
                        help="camera mode (default %(default)s; set the fps just below the rate the module "
                             "reaches on the camera)")
    parser.add_argument("--headless", action="store_true",
                        help="start the module at power-on without USB (config/initscript.cfg)")
    parser.add_argument("--dry-run", action="store_true", help="print what would change and write nothing")
    parser.add_argument("--force", action="store_true",
                        help="rewrite write-protected files, and comment out settings of yours on the card that the "
                             "new module refuses (both are backed up first)")
    parser.add_argument("--module-dir", default=None, metavar="DIR",
                        help="module folder to install (default: the repository's jevois_module/ForaNavTrees)")


def plan_from_args(args: argparse.Namespace) -> tuple[card.DeployPlan, CameraMode, list[str]]:
    """Everything checked and planned, nothing written: (plan, mode, notes)."""
    mode = parse_mode(args.mode)
    vendor = module_files.check_name("vendor", args.vendor)
    folder = args.module_dir or module_files.default_module_folder()
    module_folder = module_files.read_module_folder(folder)
    state = card.read_card(args.sd, vendor, module_files.MODULE_NAME)
    on_card = card.module_dir(vendor, module_files.MODULE_NAME)
    card_files = {name: card.decode(state.files[on_card + "/" + name]) for name in module_files.GENERATED_NAMES
                  if on_card + "/" + name in state.files}
    payload = module_files.build_module_payload(module_folder, vendor, mode, card_files=card_files,
                                                force=args.force, card_label=str(Path(args.sd) / on_card))
    plan = card.plan_deploy(state, payload.files, vendor, module_files.MODULE_NAME, mode, args.headless)
    card.preflight(args.sd, plan, args.force)
    notes = list(payload.notes)
    if not is_calibrated_size(mode):
        notes.append("the flight app's camera model is calibrated at 352x288: set its app.camWidth=%d and "
                     "app.camHeight=%d (its focal length scales with the width)" % (mode.width, mode.height))
    return plan, mode, notes


def run(args: argparse.Namespace) -> int:
    plan, mode, notes = plan_from_args(args)
    if not args.dry_run:
        card.apply_plan(args.sd, plan)
    for line in card.describe_plan(plan, args.sd, args.dry_run) + ["note: " + note for note in notes]:
        print(line)
    if not args.dry_run:
        changed = len(card.changed_paths(plan))
        print("%s/%s %s installed (%d file%s changed). Eject the card, put it in the camera and power it; "
              "check the output with a serial terminal at 115200 8N1."
              % (args.vendor, module_files.MODULE_NAME, format_mode(mode), changed, "" if changed == 1 else "s"))
    return 0
