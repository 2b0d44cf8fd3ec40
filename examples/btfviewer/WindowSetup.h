// btfviewer's window: one that fits the screen when the command line (--window, --screen) and
// the environment (OSG_WINDOW, OSG_SCREEN, OSG_CONFIG_FILE) chose none, smaller ones when it
// does not open, and the X server's own words when nothing opens.
//
// Why not osgViewer's default (AcrossAllScreens): it asks the windowing system for the screen's
// size once, on a connection of its own, and opens a window of that size without looking at the
// answer. A failed query answers 0 x 0 ("Unable to open display"), and a 0 x 0 window is X's
// BadValue (CreateWindow). Xvfb as xvfb-run starts it (no -noreset) resets itself whenever its
// last client disconnects, so the connection right after osgViewer's own screen count often
// finds it resetting: stock osgviewer failed 4 to 5 times in 8 on a 640x480 screen of this
// machine, never with -noreset (examples/README.md, "Which window").
#pragma once

#include <string>

#include <osgViewer/Viewer>

namespace btfviewer {

/** Opens the viewer's window and realizes the viewer. A window the command line set up (the
 *  Viewer's constructor reads --window and --screen) or the environment names (OSG_WINDOW,
 *  OSG_SCREEN, OSG_CONFIG_FILE) is kept as it is. Otherwise: the whole screen (its size asked
 *  again while the server does not answer), then 640 x 480, then 320 x 240; a line on stdout says
 *  which opened. Throws osgBTF::Error naming DISPLAY, what was tried and what the X server said
 *  when no window opens. */
void openWindow(osgViewer::Viewer& viewer);

}  // namespace btfviewer
