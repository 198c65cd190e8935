;;;; tangled/physics-simd.lisp -- GENERATED from physics.org by 'make tangle'. Do not edit.

;; [[file:../physics.org::#JKM0PY][Which wide instructions this machine offers:1]]
(in-package #:luv-physics)
;; Which wide instructions this machine offers:1 ends here

;; [[file:../physics.org::#JKM0PY][Which wide instructions this machine offers:2]]
(defparameter *kernel-family-instruction-sets*
  '((:sse :sse4.1)
    (:avx2 :avx2))
  "Each wide kernel family and the sb-simd instruction sets its kernels need, narrowest first. #JKM0PY")

(defun instruction-set-present-p (name)
  "True if sb-simd knows the instruction set NAME and this processor and image can run it. #JKM0PY"
  (let ((set (sb-simd-internals:find-instruction-set name nil)))
    (and set (sb-simd-internals:instruction-set-available-p set) t)))

(defun available-kernel-families ()
  "The kernel families this machine can run: :SCALAR, then each wide family whose instruction sets are all present. #JKM0PY"
  (cons :scalar
        (loop for (family . sets) in *kernel-family-instruction-sets*
              when (every #'instruction-set-present-p sets)
                collect family)))
;; Which wide instructions this machine offers:2 ends here

;; [[file:../physics.org::#O07FDP][Closing the files:2]]
(register-tangled-file #.(or *compile-file-truename* *load-truename*))
;; Closing the files:2 ends here
