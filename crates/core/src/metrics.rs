//! Image metrics: RMSE, PSNR, SSIM.
