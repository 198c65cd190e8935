;;;; tools/scene-hashes.lisp -- the state hash of every scene of *physics-scenes* after STEPS (180)
;;;; steps in every kernel family this machine runs, and of every feature scene of +feature-scenes+
;;;; (its own steps, at most STEPS) general and specialised: one line each, to compare two trees
;;;; of the engine for a change that must change no bit.
;;;; Usage: LUV_TREE=/path/to/tree/ STEPS=180 sbcl --dynamic-space-size 4Gb --non-interactive \
;;;;          --load tools/scene-hashes.lisp > hashes.txt
(load (merge-pathnames "tools/boot.lisp" (sb-ext:posix-getenv "LUV_TREE")))
(in-package #:cl-user)
;; the scenes are the workshop's; a tree from before the workshop has them in luv-physics
(when (luv-load-systems (if (asdf:find-system "luv-physics/workshop" nil) "luv-physics/workshop" "luv-physics"))
  (sb-ext:exit :code 2))
(in-package #:luv-physics)
(let ((steps (parse-integer (or (sb-ext:posix-getenv "STEPS") "180"))))
  (dolist (scene *physics-scenes*)
    (dolist (family (available-kernel-families))
      (multiple-value-bind (world script) (make-scene-world (physics-scene-name scene) :kernels family)
        (dotimes (i steps) (funcall script i) (step-physics-world world))
        (format t "~&scene ~(~A~) ~(~A~) ~D ~D~%" (physics-scene-name scene) family steps
                (physics-world-state-hash world))
        (finish-output))))
  (dolist (entry +feature-scenes+)
    (dolist (kind '(:general :specialised))
      (dolist (family (available-kernel-families))
        (multiple-value-bind (world before)
            (feature-scene (first entry) :features (if (eq kind :specialised) (or (third entry) +physics-features+) +physics-features+)
                                         :kernels family)
          (dotimes (i (min steps (fifth entry))) (when before (funcall before i)) (step-physics-world world))
          (format t "~&feature ~(~A~) ~(~A~) ~(~A~) ~D~%" (first entry) kind family (physics-world-state-hash world))
          (finish-output))))))
(sb-ext:exit)
