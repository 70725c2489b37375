#pragma once
// The payload of each soundbank section (docs/soundbank-format.md), one writer and one reader
// per section; soundbank.cpp frames them with the header, the section table and the checksums.
#include "binary_io.hpp"
#include "chladni/core/soundbank.hpp"

namespace chladni::soundbank_sections {

binary_io::Writer write_material(const Material& m);
binary_io::Writer write_modes(const Soundbank& b);
binary_io::Writer write_surface(const Soundbank& b);
binary_io::Writer write_shapes(const Soundbank& b);
binary_io::Writer write_transfer(const Transfer& t);

// Each reader fails through r (naming the file and the section) and consumes the whole payload.
Material read_material(binary_io::Reader& r);
void read_modes(binary_io::Reader& r, Soundbank& b);
void read_surface(binary_io::Reader& r, Soundbank& b);
void read_shapes(binary_io::Reader& r, Soundbank& b);  // after read_modes and read_surface
Transfer read_transfer(binary_io::Reader& r, std::size_t mode_count);

}  // namespace chladni::soundbank_sections
