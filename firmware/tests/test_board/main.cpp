// doctest main of the board tests (the Uno actuator stack against fake hardware).
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>
