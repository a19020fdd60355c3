import math
import os

import cv2
import libjevois as jevois

import foranav_detector
import foranav_model
import foranav_serial

SERSTYLES = ("Terse", "Normal")
FRAMEMARKS = ("Stop", "None")
SPECIES_FILES = {"oil_palm": "foranav_oil_palm.npz", "citrus": "foranav_citrus.npz", "olive": "foranav_olive.npz"}
BOX_COLOUR = (0, 255, 0)  # BGR
TEXT_COLOUR = (255, 255, 255)
MIN_WINDOW_PX = 24  # the HOG window a window is downscaled to
# Before the first frame the frame size is unknown: no window can exceed the shorter side of the largest
# JeVois-A33 sensor mode (1280x1024). Once frames arrive, windows must fit the frame itself.
MAX_FRAME_SIDE_PX = 1024
MAX_TREES_LIMIT = 100  # far above what a frame holds or the serial port carries; a sanity bound


## Detect oil palm (or citrus, olive) trees with the ForaNav enhanced hierarchical HOG detector
#
# Each frame is scanned with square sliding windows of several sizes. A window is a tree when (paper
# "ForaNav", section III-A): a linear SVM on the HOG of its value channel downscaled to 24x24 px finds the
# star shape of the fronds; its hue and saturation histograms correlate with the species' template
# (rejects roofs and road crossings); and the variance of the global orientation histogram of its
# full-resolution HOG, divided by the window's contrast so dim and blurred crowns are judged alike, is high
# enough (needle-like leaflets; rejects other palm species). Overlapping windows are merged and their
# centres averaged.
#
# Serial messages, per frame, best tree first (standardized coordinates, integers):
#   T2 x y                     (serstyle Terse, default) or
#   N2 <species> x y w h       (serstyle Normal)
#   MARK STOP                  end of frame (framemark Stop, default), sent even when no tree is seen so that
#                              a receiver can tell "frame done, nothing seen" from "link silent", and even
#                              when the frame could not be processed (the error is logged once per cause).
#
# Settings are jevois Parameters (setpar/getpar, params.cfg) and the same at the console through
# "foranav <name> [<value>]" (see supportedCommands). Every setting is checked on the way in (a Parameter
# callback, so setpar and params.cfg alike): a value that would break the frames is refused with an error,
# and the old value stays. Model files foranav_<species>.npz sit next to this file.
#
# Needs JeVois >= 1.18 (init() and jevois.Parameter); Python 3.7, numpy 1.16 and OpenCV 4 only.
#
# @author ForaNav project
# @displayname ForaNav Trees
# @videomapping NONE 0 0 0.0 YUYV 352 288 15.0 ForaNav ForaNavTrees
# @videomapping YUYV 352 288 15.0 YUYV 352 288 15.0 ForaNav ForaNavTrees
# @email none
# @mainurl none
# @license MIT
# @distribution Unrestricted
# @restrictions None
# @ingroup modules
class ForaNavTrees:
    # ###################################################################################################
    ## Constructor: kept cheap (slow constructors upset USB timing); the model is loaded in init()
    def __init__(self):
        self.timer = jevois.Timer("ForaNavTrees", 100, jevois.LOG_INFO)
        self.folder = os.path.dirname(os.path.abspath(__file__))
        self.detector = None
        self.loaded = (None, None)  # (species, settings key) the detector was built for
        self.params = {}
        self.frameSize = None  # (width, height) of the last frame: windows must fit it
        self.lastError = None  # the last frame error logged, so that a failing frame logs once, not at 15 fps

    # ###################################################################################################
    ## Create the parameters and load the default model
    def init(self):
        pc = jevois.ParameterCategory("ForaNav Trees", "ForaNav tree detector settings")
        self.model = self.loadModel("oil_palm")
        self.loaded = ("oil_palm", None)  # settings are read on the first frame (after params.cfg)
        self.addParam(pc, "species", "str", "Species model: oil_palm, citrus, olive, or a .npz file in the "
                      "module folder", "oil_palm")
        self.addParam(pc, "svmthresh", "str", "Top-layer SVM score a window must exceed, or auto (the species "
                      "model's)", "auto")
        self.addParam(pc, "varthresh", "str", "Bottom-layer texture (contrast-normalised global HOG histogram, "
                      "1/px^2) a tree must exceed, or auto (the species model's)", "auto")
        self.addParam(pc, "hsthresh", "str", "Mean hue/saturation Pearson correlation with the template a "
                      "tree must exceed, or auto (the species model's)", "auto")
        self.addParam(pc, "edgethresh", "str", "SVM score a window touching the frame edge must also exceed "
                      "(a crown cut by the edge), auto (the species model's) or off", "auto")
        self.addParam(pc, "windows", "str", "Window sides in pixels, comma-separated, or auto (the model's, "
                      "scaled to the frame width)", "auto")
        self.addParam(pc, "step", "int", "Window step in downscaled pixels: W*step/24 in the frame "
                      "(8 = W/3 as in the paper)", foranav_detector.DEFAULT_STEP)
        self.addParam(pc, "grouping", "str", "Peaks to trees: nms (overlap suppression, the default) or period "
                      "(suppression within 0.6 planting periods: touching crowns stay apart)", "nms")
        self.addParam(pc, "periodpx", "str", "Planting period in pixels for grouping period (e.g. the map's tree "
                      "spacing at the current height), or auto (from each frame's autocorrelation)", "auto")
        self.addParam(pc, "maxtrees", "int", "At most this many trees reported per frame, best first",
                      foranav_detector.DEFAULT_MAX_DETECTIONS)
        self.addParam(pc, "serstyle", "str", "Serial message per tree: Terse (T2 x y) or Normal "
                      "(N2 species x y w h)", "Terse")
        self.addParam(pc, "framemark", "str", "End-of-frame message: Stop (MARK STOP) or None", "Stop")
        for name in self.params:
            if hasattr(self.params[name], "setCallback"):
                self.params[name].setCallback(self.settingCheck(name))

    ## A Parameter callback: raise (the engine's "ERR ...") for a value that would break the frames
    def settingCheck(self, name):
        def check(value):
            error = checkSetting(name, str(value), self.frameSize) or self.checkSpecies(name, str(value))
            if error:
                raise ValueError(error)
        return check

    def addParam(self, category, name, kind, description, default):
        self.params[name] = jevois.Parameter(self, name, kind, description, default, category)

    def loadModel(self, species):
        path = os.path.join(self.folder, SPECIES_FILES.get(species, species))
        return foranav_model.load_model(path)

    # ###################################################################################################
    ## Rebuild the detector when a setting changed (cheap comparison every frame)
    def currentDetector(self):
        species = self.params["species"].get()
        key = (species, self.params["svmthresh"].get(), self.params["varthresh"].get(),
               self.params["hsthresh"].get(), self.params["windows"].get(), self.params["step"].get(),
               self.params["maxtrees"].get(), self.params["edgethresh"].get(), self.params["grouping"].get(),
               self.params["periodpx"].get())
        if self.loaded[1] != key:
            if self.loaded[0] != species:
                self.model = self.loadModel(species)
            settings = foranav_detector.DetectorSettings(
                svm_threshold=parseThreshold(key[1]), variance_threshold=parseThreshold(key[2]),
                hs_threshold=parseThreshold(key[3]), window_sizes=parseWindows(key[4]), step=key[5],
                max_detections=key[6], edge_threshold=parseEdgeThreshold(key[7]), grouping=key[8],
                period_px=parsePeriod(key[9]))
            self.detector = foranav_detector.TreeDetector(self.model, settings)
            self.loaded = (species, key)
        return self.detector

    # ###################################################################################################
    ## Detect and send one serial line per tree, then the end-of-frame mark
    def detectAndSend(self, img):
        height, width = img.shape[0], img.shape[1]
        self.frameSize = (width, height)
        try:
            trees = self.currentDetector().detect(img)
            self.lastError = None
        except Exception as err:  # the engine keeps running: the frame still ends with its mark
            trees = []
            self.logFrameError(err)
        normal = self.params["serstyle"].get() == "Normal"
        for tree in trees:
            if normal:
                jevois.sendSerial(foranav_serial.format_n2(self.model.species, tree.x, tree.y, tree.w, tree.h,
                                                           width, height))
            else:
                jevois.sendSerial(foranav_serial.format_t2(tree.x, tree.y, width, height))
        if self.params["framemark"].get() == "Stop":
            jevois.sendSerial(foranav_serial.FRAME_STOP)
        return trees

    def logFrameError(self, err):
        message = "ForaNavTrees: frame not processed: %s" % err
        if message != self.lastError:
            jevois.LERROR(message)
            self.lastError = message

    # ###################################################################################################
    ## Process function with no USB output (flight)
    def processNoUSB(self, inframe):
        img = inframe.getCvBGR()
        self.timer.start()
        self.detectAndSend(img)
        self.timer.stop()

    # ###################################################################################################
    ## Process function with USB output (debugging): boxes, scores and the frame rate on the video
    def process(self, inframe, outframe):
        img = inframe.getCvBGR()
        self.timer.start()
        trees = self.detectAndSend(img)
        for tree in trees:
            x0, y0 = int(round(tree.x - tree.w / 2.0)), int(round(tree.y - tree.h / 2.0))
            x1, y1 = int(round(tree.x + tree.w / 2.0)), int(round(tree.y + tree.h / 2.0))
            cv2.rectangle(img, (x0, y0), (x1, y1), BOX_COLOUR, 2)
            cv2.drawMarker(img, (int(round(tree.x)), int(round(tree.y))), BOX_COLOUR, cv2.MARKER_CROSS, 10, 1)
            cv2.putText(img, "%.2f" % tree.score, (x0 + 3, max(12, y0 + 14)), cv2.FONT_HERSHEY_SIMPLEX, 0.45,
                        BOX_COLOUR, 1, cv2.LINE_AA)
        fps = self.timer.stop()
        cv2.putText(img, "ForaNav %s: %d" % (self.model.species, len(trees)), (3, 15), cv2.FONT_HERSHEY_SIMPLEX,
                    0.5, TEXT_COLOUR, 1, cv2.LINE_AA)
        cv2.putText(img, fps, (3, img.shape[0] - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.5, TEXT_COLOUR, 1, cv2.LINE_AA)
        outframe.sendCv(img)

    # ###################################################################################################
    ## Console commands: the same settings as the parameters
    def parseSerial(self, command):
        words = command.split()
        if not words or words[0] != "foranav":
            return "ERR Unsupported command"
        if len(words) == 1:
            return " ".join("%s=%s" % (name, self.params[name].get()) for name in sorted(self.params))
        name = words[1]
        if name not in self.params:
            return "ERR Unknown setting %s (one of: %s)" % (name, ", ".join(sorted(self.params)))
        if len(words) == 2:
            return "%s=%s" % (name, self.params[name].get())
        error = checkSetting(name, words[2], self.frameSize) or self.checkSpecies(name, words[2])
        if error:
            return "ERR " + error
        current = self.params[name].get()
        try:
            self.params[name].set(type(current)(words[2]))
        except ValueError as err:
            return "ERR %s" % err
        return ""

    def checkSpecies(self, name, value):
        if name == "species" and not os.path.isfile(os.path.join(self.folder, SPECIES_FILES.get(value, value))):
            return "no model file for species %s" % value
        return ""

    def supportedCommands(self):
        return ("foranav - list the tree detector settings\n"
                "foranav <name> - show one setting\n"
                "foranav <name> <value> - change a setting (species, svmthresh|varthresh|hsthresh <number>|auto, "
                "edgethresh <number>|auto|off, windows <px,px>|auto, step, grouping nms|period, "
                "periodpx <px>|auto, maxtrees, serstyle Terse|Normal, framemark Stop|None)")


def parseThreshold(text):
    """'auto' -> None (the model's threshold); '0.5' -> 0.5; ValueError for nan or inf."""
    text = text.strip()
    if text in ("", "auto"):
        return None
    value = float(text)
    if math.isnan(value) or math.isinf(value):
        raise ValueError("not a finite number: %s" % text)
    return value


def parseEdgeThreshold(text):
    """'auto' -> None (the model's); 'off' -> no extra test at the frame edge; '0' -> 0.0."""
    text = text.strip()
    if text == "off":
        return foranav_detector.EDGE_TEST_OFF
    return parseThreshold(text)


def parsePeriod(text):
    """'auto' -> None (estimated from each frame); '96' -> 96.0; ValueError unless a positive finite number."""
    value = parseThreshold(text)
    if value is not None and value <= 0:
        raise ValueError("not a positive number: %s" % text)
    return value


def parseWindows(text):
    """'auto' -> None (the model's sizes); '72,96' -> (72.0, 96.0)."""
    text = text.strip()
    if text in ("", "auto"):
        return None
    return tuple(float(part) for part in text.split(","))


def checkSetting(name, value, frameSize=None):
    """'' when value is acceptable for the named setting, otherwise the reason.

    frameSize (width, height): the frame windows must fit (None: not known yet, any sensor mode)."""
    try:
        if name in ("svmthresh", "varthresh", "hsthresh"):
            parseThreshold(value)
        elif name == "edgethresh":
            parseEdgeThreshold(value)
        elif name == "step":
            if not 1 <= int(value) <= MIN_WINDOW_PX:
                return "step out of range (1 to %d)" % MIN_WINDOW_PX
        elif name == "maxtrees":
            if not 1 <= int(value) <= MAX_TREES_LIMIT:
                return "maxtrees out of range (1 to %d)" % MAX_TREES_LIMIT
        elif name == "periodpx":
            parsePeriod(value)
        elif name == "grouping" and value not in foranav_detector.GROUPINGS:
            return "grouping must be one of %s" % ", ".join(foranav_detector.GROUPINGS)
        elif name == "windows":
            return checkWindows(parseWindows(value), frameSize)
        elif name == "serstyle" and value not in SERSTYLES:
            return "serstyle must be one of %s" % ", ".join(SERSTYLES)
        elif name == "framemark" and value not in FRAMEMARKS:
            return "framemark must be one of %s" % ", ".join(FRAMEMARKS)
    except ValueError:
        return "bad value for %s: %s" % (name, value)
    return ""


def checkWindows(windows, frameSize):
    if windows is None:
        return ""
    if not all(MIN_WINDOW_PX <= w < float("inf") for w in windows):
        return "windows must be at least %d px" % MIN_WINDOW_PX
    largest = MAX_FRAME_SIDE_PX if frameSize is None else min(frameSize)
    if max(windows) > largest:
        where = "any sensor mode" if frameSize is None else "the %dx%d frame" % frameSize
        return "windows of %g px do not fit %s (at most %d px)" % (max(windows), where, largest)
    return ""
