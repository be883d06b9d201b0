#pragma once
/// Heights from gradients: least-squares (Poisson) integration with Neumann boundaries, solved
/// exactly with a discrete cosine transform (FFTW REDFT10 / REDFT01).
///
/// Discretisation: gradients are given at pixel centres and averaged onto the faces between
/// neighbouring pixels (trapezoid rule, second-order accurate); the 5-point Laplacian with
/// reflecting borders is then solved for the divergence of those face fluxes. Only interior
/// faces carry flux, which is exactly the DCT operator's boundary, so a linear ramp is recovered
/// to rounding error and smooth fields with an O(spacing^2) error.
#include <tdf/core/image.h>

#include <string>

namespace tdf {

/// Integrates `gx` = dh/dx (x = column index, to the right) and `gy` = dh/dy (y = row index,
/// downwards), both 1-channel in height units per pixel and of equal size (at least 2 x 2).
/// Returns h with zero mean, in the same height units. Throws tdf::Error on mismatched sizes or
/// non-finite values (naming `what`).
Image integrate_gradients(const Image& gx, const Image& gy, const std::string& what = "gradients");

/// Central-difference gradients of a 1-channel image (one-sided on the borders), in the
/// conventions of integrate_gradients: x to the right, y down, units per pixel.
void height_gradients(const Image& height, Image& gx, Image& gy);

}  // namespace tdf
