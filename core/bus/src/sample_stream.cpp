#include "spindown/sample_stream.hpp"

namespace spindown {

std::optional<Quantity> quantity_from_samples_code(std::int8_t code) {
  switch (code) {
    case samples_t::QUANTITY_BACK_EMF_V: return Quantity::back_emf_volts;
    case samples_t::QUANTITY_RPM: return Quantity::rpm;
    case samples_t::QUANTITY_RAD_S: return Quantity::rad_per_s;
    default: return std::nullopt;
  }
}

std::int8_t samples_code_of(Quantity quantity) {
  switch (quantity) {
    case Quantity::back_emf_volts: return samples_t::QUANTITY_BACK_EMF_V;
    case Quantity::rpm: return samples_t::QUANTITY_RPM;
    case Quantity::rad_per_s: return samples_t::QUANTITY_RAD_S;
  }
  return samples_t::QUANTITY_BACK_EMF_V;
}

}  // namespace spindown
