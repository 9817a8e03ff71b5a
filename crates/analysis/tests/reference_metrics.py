"""Reference values for crates/analysis/tests/image_reference.rs, from independent tools:
scikit-image (SSIM, PSNR, CIEDE2000 and sRGB -> Lab) and NVIDIA's own FLIP package
(flip-evaluator, LDR-FLIP at 67 pixels per degree).

    python3 -m venv venv && venv/bin/pip install numpy scikit-image flip-evaluator
    venv/bin/python crates/analysis/tests/reference_metrics.py

The two 48x40 test images are integer formulas, built identically in the Rust test.
"""
import numpy as np
import flip_evaluator
from skimage.color import deltaE_ciede2000, rgb2lab
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

W, H = 48, 40


def images():
    ref = np.zeros((H, W, 3), np.uint8)
    test = np.zeros((H, W, 3), np.uint8)
    for y in range(H):
        for x in range(W):
            r = [(x * 7 + y * 3) % 256, (x * y) % 256, ((x + 2 * y) * 5) % 256]
            ref[y, x] = r
            d = (x * 31 + y * 17) % 21 - 10
            test[y, x] = [min(255, max(0, c + d * (k + 1))) for k, c in enumerate(r)]
    return ref, test


def luma(img):
    f = img.astype(np.float64) / 255.0
    return 0.2126 * f[..., 0] + 0.7152 * f[..., 1] + 0.0722 * f[..., 2]


ref, test = images()
ssim = structural_similarity(luma(ref), luma(test), gaussian_weights=True, sigma=1.5,
                             use_sample_covariance=False, data_range=1.0)
psnr = peak_signal_noise_ratio(ref, test, data_range=255)
de = deltaE_ciede2000(rgb2lab(ref), rgb2lab(test))
flat = np.sort(de.ravel())
p99 = flat[int(np.ceil(0.99 * flat.size)) - 1]
_, flip_mean, _ = flip_evaluator.evaluate(ref.astype(np.float32) / 255.0,
                                         test.astype(np.float32) / 255.0, "LDR",
                                         applyMagma=False)
print(f"ssim {ssim:.10f}\npsnr {psnr:.10f}\nde_mean {de.mean():.10f}\nde_p99 {p99:.10f}")
print(f"de_max {de.max():.10f}\nabove_1 {(de > 1).mean():.10f}\nabove_2.3 {(de > 2.3).mean():.10f}")
print(f"flip_mean {flip_mean:.10f}")
