// DRAPE_VERSION, the program's version: the build passes project(VERSION);
// "unknown" for a file compiled without it, so a stored version is never empty.
#pragma once

#ifndef DRAPE_VERSION
#define DRAPE_VERSION "unknown"
#endif
