#pragma once
/// @file
/// Umbrella header.
#include <stabint/batch.hpp>
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/events.hpp>
#include <stabint/io.hpp>
#include <stabint/options_table.h>
#include <stabint/reporters.hpp>
#include <stabint/scene.hpp>
#include <stabint/simulator.hpp>
#include <stabint/types.hpp>
