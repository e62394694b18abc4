// Part of the check's own test tree (tests/layering/bad): a header the violations name.
#pragma once
