#pragma once
// The contact terms of a result file (result_file.hpp): per contact term its
// name and body, and per output frame its force, where it acts, its deepest
// penetration and its active samples.
//
//   /contacts/<c>/term             string, c = 0..C-1 (ContactTrack::term: "contact:<object>",
//                                  "skin_contact", "body_contact", "self_contact")
//   /contacts/<c>/body             string, the body it acts on
//   /contacts/<c>/force            (Fr,3)  N, world, on the body
//   /contacts/<c>/point            (Fr,3)  m, world, where it acts (ContactFrame::point)
//   /contacts/<c>/max_penetration  (Fr,)   m
//   /contacts/<c>/active_samples   (Fr,)   whole numbers (float64): samples or capsule pairs in contact
// Only when C > 0; absent in files written before contacts were stored (read
// as no contacts).
#include <string>
#include <vector>

#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

/// Writes each contact's /contacts/<c>/term and body and creates its per-frame
/// datasets (nothing when `contacts` is empty; their frames are not written).
void create_contact_datasets(io::Hdf5File& file, const std::vector<ContactTrack>& contacts);

/// Appends one frame of every contact (one ContactFrame per track given to
/// create_contact_datasets, same order). `at` starts messages (file and
/// frame); throws naming the contact on a count mismatch or a non-finite value.
void append_contact_frames(io::Hdf5File& file, const std::vector<ContactTrack>& contacts,
                           const std::vector<ContactFrame>& frames, const std::string& at);

/// Reads /contacts (F frames each); empty when the file has none. Throws one
/// error naming the file and the dataset on a missing or misshapen dataset,
/// a negative depth or a count that is not a whole number ≥ 0.
std::vector<ContactTrack> read_contacts(const io::Hdf5File& file, std::int64_t frames);

/// A contact's largest |force| over its frames (N), and the frame it is at (-1 without frames).
double peak_contact_force(const ContactTrack& contact, int* frame = nullptr);

/// Lines for `sflsh inspect`: "contact <term> on <body>: peak force F N at
/// t = T s, max penetration P mm, up to N active samples", one per contact,
/// each ending in a newline; empty without contacts.
std::string describe_contacts(const SimulationResult& result);

}  // namespace sflsh
